#include "vtb/solvers/implicit_euler.hh"

#include "vtb/springs/force_jacobian.hh"

#include <algorithm>
#include <limits>

namespace vtb {
namespace {

/// The free-dof system's pattern, values 1 (the first factorisation only sizes the factor).
template <int dim> Eigen::SparseMatrix<double> block_pattern(const Model<dim>& model) {
  Eigen::SparseMatrix<double> A =
      free_block_pattern(model.net, model.free_index, static_cast<int>(model.free_nodes.size()));
  A.coeffs().setOnes();
  return A;
}

} // namespace

template <int dim>
ImplicitEuler<dim>::ImplicitEuler(const Model<dim>& model, double dt)
    : Integrator<dim>(dt), m_model(model), m_solver(block_pattern(model)) {
  const auto& net = model.net;
  const int n = static_cast<int>(m_solver.size());
  // Each stored (upper, ordered) entry is reached exactly once: diagonal blocks add the
  // entries whose ordered row <= column; the off-diagonal block (a, b) owns the pair
  // {(a p, b q), (b q, a p)}.
  m_slot.assign(static_cast<std::size_t>(net.num_springs()) * dim * dim, {-1, -1, -1});
  for (int s = 0; s < net.num_springs(); ++s) {
    const int a = model.free_index[static_cast<std::size_t>(net.edge[static_cast<std::size_t>(s)][0])];
    const int b = model.free_index[static_cast<std::size_t>(net.edge[static_cast<std::size_t>(s)][1])];
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q) {
        auto& slot = m_slot[static_cast<std::size_t>((s * dim + p) * dim + q)];
        auto diag = [&](int x) {
          const int r = m_solver.ordered(x * dim + p), c = m_solver.ordered(x * dim + q);
          return r <= c ? m_solver.offset(r, c) : -1;
        };
        if (a >= 0) slot[0] = diag(a);
        if (b >= 0) slot[1] = diag(b);
        if (a >= 0 && b >= 0) slot[2] = m_solver.offset(m_solver.ordered(a * dim + p), m_solver.ordered(b * dim + q));
      }
  }
  // The volume term's: per cell, its blocks (a, b) with a <= b (the transposed block is the
  // same stored pair), the diagonal ones by their upper entries as above.
  constexpr int nb = (dim + 1) * (dim + 1) * dim * dim;
  m_cell_slot.assign(static_cast<std::size_t>(net.volume.size()) * nb, -1);
  for (int c = 0; c < net.volume.size(); ++c)
    for (int x = 0; x <= dim; ++x)
      for (int y = x; y <= dim; ++y) {
        const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
        const int a = model.free_index[static_cast<std::size_t>(cell[x])];
        const int b = model.free_index[static_cast<std::size_t>(cell[y])];
        if (a < 0 || b < 0) continue;
        for (int p = 0; p < dim; ++p)
          for (int q = 0; q < dim; ++q) {
            const int r = m_solver.ordered(a * dim + p), col = m_solver.ordered(b * dim + q);
            if (x == y && r > col) continue;
            m_cell_slot[static_cast<std::size_t>(c * nb + ((x * (dim + 1) + y) * dim + p) * dim + q)] =
                static_cast<int>(m_solver.offset(r, col));
          }
      }
  m_diag_slot.resize(static_cast<std::size_t>(n));
  for (int d = 0; d < n; ++d)
    m_diag_slot[static_cast<std::size_t>(d)] = m_solver.offset(m_solver.ordered(d), m_solver.ordered(d));
  m_force.resize(dim, model.num_nodes());
  m_rhs.resize(n, 1);
  // One factorisation of the pattern's values sizes the factor's own workspace (Eigen sizes its
  // diagonal at the first factorize), so that no step allocates, the first included: the tensor
  // filter's safety net may take its first step at any time (its outcome does not matter here).
  m_solver.factorize();
}

template <int dim> void ImplicitEuler<dim>::step(State<dim>& s) {
  const double dt = this->dt();
  const auto& net = m_model.net;
  const auto& fi = m_model.free_index;
  double* A = m_solver.values();
  std::fill(A, A + m_solver.nonzeros(), 0.0);
  const auto nf = static_cast<int>(m_model.free_nodes.size());
  for (int a = 0; a < nf; ++a) {
    const int i = m_model.free_nodes[static_cast<std::size_t>(a)];
    // The mass, and the couplings' dt^2 k + dt c (a pull, a haptic contact) solved with it.
    const double m = net.mass[i] * (1.0 + dt * net.mass_damping) + coupling_diagonal(s, i, dt);
    for (int p = 0; p < dim; ++p) A[m_diag_slot[static_cast<std::size_t>(a * dim + p)]] += m;
  }
  // Right-hand side dt (f + f_ext + dt K v) and the matrix, spring by spring.
  m_model.external_forces(s.t + dt, m_force);
  if (s.applied.cols() == m_force.cols()) m_force += s.applied;
  add_internal_forces(net, s.u, s.v, m_force);
  for (int i : m_model.free_nodes) m_force.col(i) += coupling_force_correction(s, i, dt);
  // The matrix M + dt^2 K + dt D in stiffness signs: each block of the shared assembly enters
  // with -sign (df_i/du_i = -K_s). The upper triangle is stored: diagonal blocks through
  // slots 0 and 1, the off-diagonal pair once, at the (i, j) block.
  for_each_jacobian_block(net, s.u, true, [&](int sp, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
    const auto* slot = &m_slot[static_cast<std::size_t>(sp * dim * dim)];
    const int which = i == j ? (i == net.edge[static_cast<std::size_t>(sp)][0] ? 0 : 1) : 2;
    if (which == 2 && i != net.edge[static_cast<std::size_t>(sp)][0]) return; // (j, i): stored once
    if (which == 2) {
      // df_i/dx_j = K and df_i/dx_i = -K, so the K v term of node i is K (v_j - v_i).
      const Vec<dim> kv = dt * (K * (s.v.col(j) - s.v.col(i)));
      m_force.col(i) += kv;
      m_force.col(j) -= kv;
      if (fi[static_cast<std::size_t>(i)] < 0 || fi[static_cast<std::size_t>(j)] < 0) return;
    }
    const Mat<dim> B = -sign * (dt * dt * K + dt * D);
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q) {
        const int at = slot[p * dim + q][which];
        if (at >= 0) A[at] += B(p, q);
      }
  });
  // The volume term's blocks (Gauss-Newton: positive semidefinite, as the springs' clamp):
  // its K v term block by block, the matrix through the cells' slots.
  constexpr int nb = (dim + 1) * (dim + 1) * dim * dim;
  for_each_cell_block(net.volume, net.rest, s.u, true, [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>& D) {
    const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
    m_force.col(cell[x]) += dt * (K * s.v.col(cell[y]));
    if (y < x) return;
    const Mat<dim> B = -(dt * dt * K + dt * D);
    const int* at = &m_cell_slot[static_cast<std::size_t>(c * nb + (x * (dim + 1) + y) * dim * dim)];
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q)
        if (at[p * dim + q] >= 0) A[at[p * dim + q]] += B(p, q);
  });
  for (int a = 0; a < nf; ++a) {
    const int i = m_model.free_nodes[static_cast<std::size_t>(a)];
    for (int p = 0; p < dim; ++p) m_rhs(m_solver.ordered(a * dim + p), 0) = dt * m_force(p, i);
  }
  if (!m_solver.factorize()) {
    // Not positive definite: only a non-finite state does this with the clamped Jacobian.
    // Poison the state so that the caller's stability watch stops the run.
    s.v.setConstant(std::numeric_limits<double>::quiet_NaN());
    s.t += dt;
    return;
  }
  m_solver.solve_in_place(m_rhs);
  for (int a = 0; a < nf; ++a) {
    const int i = m_model.free_nodes[static_cast<std::size_t>(a)];
    for (int p = 0; p < dim; ++p) s.v(p, i) += m_rhs(m_solver.ordered(a * dim + p), 0);
    s.u.col(i) += dt * s.v.col(i);
  }
  s.t += dt;
  m_model.apply_constraints(s.t, s.u, s.v);
}

template class ImplicitEuler<2>;
template class ImplicitEuler<3>;

} // namespace vtb
