#include "vtb/solvers/tensor_filter.hh"

#include <Eigen/LU>

// The tensor filter's couplings (a tool tip's footprint, the drags' patches): their columns of
// the Woodbury update in the solve's frame, and the correction they make to a solve.
namespace vtb {

template <int dim> double TensorFilter<dim>::coupling_entry(int u, int q, int p, int axis) const {
  // U's column (u, p) in the solve's (rotated) frame at node q's axis `axis`: w_q R_q^T e_p. A
  // unit of one node spans the same columns as e_p (its coupling is isotropic), so its columns
  // stay e_p and need no new solve when the node turns; a footprint's nodes turn apart, and its
  // w w^T in the world frame is R^T (w w^T) R in the rotated one.
  const double w = m_set->weight(u, q);
  if (m_set->size(u) == 1) return p == axis ? w : 0.0;
  return w * rotation(m_set->node(u, q))(p, axis);
}

template <int dim> void TensorFilter<dim>::couple(const CouplingSet<dim>& set) {
  const int count = set.units();
  std::array<double, kMaxCoupled> c{}; // dt^2 k + dt b per unit
  bool groups = false;                 // units of several nodes: their columns turn with the nodes
  for (int u = 0; u < count; ++u) {
    c[static_cast<std::size_t>(u)] = set.coefficient(u);
    groups = groups || set.size(u) > 1;
  }
  const bool new_z = count > 0 && (set.version() != m_set_version || m_z_version != m_factor_version ||
                                   (groups && m_z_turns != m_turns));
  const bool same_set = m_set == &set;
  m_set = &set;
  if (same_set && !new_z && count == m_coupled && c == m_coupled_k) return;
  m_coupled = count;
  m_coupled_k = c;
  if (count == 0) return;
  const int m = count * dim;
  // Where unit u's node q sits in the solve's vector on axis `axis`.
  const auto at = [&](int u, int q, int axis) {
    return m_index[static_cast<std::size_t>(set.slot(u, q) * dim + axis)];
  };
  if (new_z || !same_set) { // Z = H^-1 U: one solve per unit and axis, in place in its column
    for (int col = 0; col < m; ++col) {
      auto z = m_z.col(col);
      z.setZero();
      for (int q = 0; q < set.size(col / dim); ++q)
        for (int axis = 0; axis < dim; ++axis)
          z[at(col / dim, q, axis)] += coupling_entry(col / dim, q, col % dim, axis);
      m_h->solve(z);
    }
    m_z_version = m_factor_version;
    m_set_version = set.version();
    m_z_turns = m_turns;
  }
  Small C = Small::Zero(m, m);
  for (int r = 0; r < m; ++r)
    for (int q = 0; q < set.size(r / dim); ++q)
      for (int axis = 0; axis < dim; ++axis)
        C.row(r) += coupling_entry(r / dim, q, r % dim, axis) * m_z.row(at(r / dim, q, axis)).head(m);
  for (int u = 0; u < count; ++u)
    m_unit_response[static_cast<std::size_t>(u)] = C.template block<dim, dim>(u * dim, u * dim);
  for (int r = 0; r < m; ++r) C(r, r) += 1.0 / m_coupled_k[static_cast<std::size_t>(r / dim)];
  m_capacitance.compute(C);
}

template <int dim> void TensorFilter<dim>::correct_for_couplings(Eigen::MatrixXd& y) const {
  const int m = m_coupled * dim;
  if (m == 0) return;
  m_small.resize(m);
  for (int r = 0; r < m; ++r) {
    double sum = 0;
    for (int q = 0; q < m_set->size(r / dim); ++q)
      for (int axis = 0; axis < dim; ++axis)
        sum += coupling_entry(r / dim, q, r % dim, axis) *
               y(m_index[static_cast<std::size_t>(m_set->slot(r / dim, q) * dim + axis)], 0);
    m_small[r] = sum;
  }
  m_small = m_capacitance.solve(m_small);
  y.col(0).noalias() -= m_z.leftCols(m) * m_small;
}

template double TensorFilter<2>::coupling_entry(int, int, int, int) const;
template void TensorFilter<2>::couple(const CouplingSet<2>&);
template void TensorFilter<2>::correct_for_couplings(Eigen::MatrixXd&) const;
template double TensorFilter<3>::coupling_entry(int, int, int, int) const;
template void TensorFilter<3>::couple(const CouplingSet<3>&);
template void TensorFilter<3>::correct_for_couplings(Eigen::MatrixXd&) const;

} // namespace vtb
