#include "vtb/solvers/warped_filter.hh"

#include "vtb/springs/force_jacobian.hh"

#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vtb {

template <int dim>
Eigen::SparseMatrix<double> tensor_filter_matrix(const Model<dim>& model, double dt, double transverse) {
  const auto& net = model.net;
  const int nf = static_cast<int>(model.free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int a = 0; a < nf; ++a)
    for (int p = 0; p < dim; ++p)
      trip.emplace_back(a * dim + p, a * dim + p,
                        net.mass[model.free_nodes[static_cast<std::size_t>(a)]] * (1.0 + dt * net.mass_damping));
  // The shared assembly at rest: blocks k n n^T and c n n^T (-sign: stiffness signs), plus
  // `transverse` times their transverse parts k (I - n n^T) and c (I - n n^T). Every entry of
  // every block is stored, so the pattern does not depend on the values.
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_jacobian_block(net, rest, false, [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    if (a < 0 || b < 0) return;
    const Mat<dim> I = Mat<dim>::Identity();
    const Mat<dim> B =
        -sign * (dt * (D + transverse * (D.trace() * I - D)) + dt * dt * (K + transverse * (K.trace() * I - K)));
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q) trip.emplace_back(a * dim + p, b * dim + q, B(p, q));
  });
  Eigen::SparseMatrix<double> H(nf * dim, nf * dim);
  H.setFromTriplets(trip.begin(), trip.end());
  return H;
}

template <int dim>
WarpedFilter<dim>::WarpedFilter(const Model<dim>& model, double dt)
    : WarpedFilter(model, dt, tensor_filter_matrix(model, dt, 0.0)) {}

template <int dim>
WarpedFilter<dim>::WarpedFilter(const Model<dim>& model, double dt, const Eigen::SparseMatrix<double>& H0)
    : m_model(model), m_h(H0), m_rotation(static_cast<std::size_t>(model.num_nodes()), Mat<dim>::Identity()),
      m_rest_dir(dim, model.net.num_springs()), m_rhs(static_cast<Eigen::Index>(model.free_nodes.size()) * dim, 1),
      m_z(static_cast<Eigen::Index>(model.free_nodes.size()) * dim, kMaxCoupled * dim),
      m_capacitance(kMaxCoupled * dim) {
  if (!m_h.factorize()) throw std::runtime_error("filtered (tensor): H is not positive definite");
  // H(beta) = H(0) + beta (H(1) - H(0)) entry by entry: both have one pattern.
  const Eigen::SparseMatrix<double> H1 = tensor_filter_matrix(model, dt, 1.0);
  m_base.assign(m_h.values(), m_h.values() + m_h.nonzeros());
  m_transverse.assign(m_base.size(), 0.0);
  for (int c = 0; c < H0.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it0(H0, c), it1(H1, c); it0; ++it0, ++it1) {
      const int r = m_h.ordered(static_cast<int>(it0.row())), cc = m_h.ordered(c);
      if (r <= cc) m_transverse[static_cast<std::size_t>(m_h.offset(r, cc))] += it1.value() - it0.value();
    }
  const auto& net = model.net;
  for (int s = 0; s < net.num_springs(); ++s)
    m_rest_dir.col(s) = (net.rest.col(net.edge[static_cast<std::size_t>(s)][1]) -
                         net.rest.col(net.edge[static_cast<std::size_t>(s)][0]))
                            .normalized();
}

template <int dim> double WarpedFilter<dim>::direction_mismatch(const Nodal<dim>& u) const {
  const auto& net = m_model.net;
  double worst = 0;
  for (int s = 0; s < net.num_springs(); ++s) {
    const auto [i, j] = net.edge[static_cast<std::size_t>(s)];
    const Vec<dim> d = net.rest.col(j) + u.col(j) - net.rest.col(i) - u.col(i);
    const double l = d.norm();
    if (!(l > 0)) continue;
    // The rest direction turned by both ends' rotations (their mean): a smooth rotation field
    // (bending) then leaves no mismatch, a distortion (shear, which turns springs apart) does.
    const Vec<dim> turned =
        (m_rotation[static_cast<std::size_t>(i)] + m_rotation[static_cast<std::size_t>(j)]) * m_rest_dir.col(s);
    const double m = (d / l - turned.normalized()).norm();
    if (!(m <= worst)) worst = m; // NaN propagates
  }
  return worst;
}

template <int dim> void WarpedFilter<dim>::cover(double mismatch) {
  // beta is set to twice the mismatch and kept while the mismatch stays between beta / 8 and
  // beta (so it must grow 2x, or fall 16x, before the next refactorisation). Mismatches below
  // 2e-3 get no cover (beta = 0: the lag-free filter). Measured (docs/method.md): half that
  // cover diverges on the paper's plate at a tenth of its stiffness; twice it doubles the
  // cantilever's error at dt = 40 ms.
  const double wanted = mismatch < 2e-3 ? 0.0 : std::min(1.0, 2 * mismatch);
  if (!std::isfinite(mismatch) || (mismatch <= m_beta && !(8 * mismatch < m_beta)) || wanted == m_beta) return;
  m_beta = wanted;
  double* v = m_h.values();
  for (std::size_t k = 0; k < m_base.size(); ++k) v[k] = m_base[k] + m_beta * m_transverse[k];
  m_h.factorize(); // H(beta) is H(0) plus positive semidefinite terms: positive definite
  ++m_factor_version;
}

template <int dim> void WarpedFilter<dim>::couple(const Eigen::VectorXd& coupling) {
  const auto& free = m_model.free_nodes;
  const int nf = static_cast<int>(free.size());
  int count = 0;
  bool same = true;
  std::array<double, kMaxCoupled> k{}; // dt^2 k + dt c per coupled node
  for (int a = 0; a < nf && count < kMaxCoupled && coupling.size() > 0; ++a) {
    const double ka = coupling[free[static_cast<std::size_t>(a)]];
    if (!(ka > 0) || !std::isfinite(ka)) continue;
    same = same && count < m_coupled && m_coupled_node[static_cast<std::size_t>(count)] == a;
    m_coupled_node[static_cast<std::size_t>(count)] = a;
    k[static_cast<std::size_t>(count++)] = ka;
  }
  same = same && count == m_coupled;
  const bool new_z = !same || m_z_version != m_factor_version;
  if (same && !new_z && k == m_coupled_k) return;
  m_coupled = count;
  m_coupled_k = k;
  if (count == 0) return;
  const int m = count * dim;
  if (new_z) { // Z = H^-1 U: one solve per coupled dof, in place in its column
    for (int c = 0; c < m; ++c) {
      auto z = m_z.col(c);
      z.setZero();
      z[m_h.ordered(m_coupled_node[static_cast<std::size_t>(c / dim)] * dim + c % dim)] = 1.0;
      m_h.solve_in_place(z);
    }
    m_z_version = m_factor_version;
  }
  Small C(m, m);
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c)
      C(r, c) = m_z(m_h.ordered(m_coupled_node[static_cast<std::size_t>(r / dim)] * dim + r % dim), c);
  for (int r = 0; r < m; ++r) C(r, r) += 1.0 / m_coupled_k[static_cast<std::size_t>(r / dim)];
  m_capacitance.compute(C);
}

template <int dim> void WarpedFilter<dim>::correct_for_couplings(Eigen::MatrixXd& y) const {
  const int m = m_coupled * dim;
  if (m == 0) return;
  m_small.resize(m);
  for (int r = 0; r < m; ++r)
    m_small[r] = y(m_h.ordered(m_coupled_node[static_cast<std::size_t>(r / dim)] * dim + r % dim), 0);
  m_small = m_capacitance.solve(m_small);
  y.col(0).noalias() -= m_z.leftCols(m) * m_small;
}

template <int dim> void WarpedFilter<dim>::rotations(const Nodal<dim>& u) {
  const auto& net = m_model.net;
  for (int i = 0; i < net.num_nodes(); ++i) {
    Mat<dim> A = Mat<dim>::Zero();
    const Vec<dim> xi = net.rest.col(i) + u.col(i);
    for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p) {
      const int j = net.adj_node[static_cast<std::size_t>(p)];
      A += (net.rest.col(j) + u.col(j) - xi) * (net.rest.col(j) - net.rest.col(i)).transpose();
    }
    Mat<dim>& R = m_rotation[static_cast<std::size_t>(i)];
    if constexpr (dim == 2) {
      // The rotation nearest to A (polar part) in closed form.
      const double angle = std::atan2(A(1, 0) - A(0, 1), A(0, 0) + A(1, 1));
      R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    } else {
      const Eigen::JacobiSVD<Mat<dim>> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Mat<dim> U = svd.matrixU();
      if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(dim - 1) *= -1;
      R = U * svd.matrixV().transpose();
    }
    if (!R.allFinite()) R.setIdentity(); // a non-finite state: the run's watch stops it
  }
}

template <int dim> double WarpedFilter<dim>::prepare(const Nodal<dim>& u) {
  rotations(u);
  const double mismatch = direction_mismatch(u);
  if (mismatch <= kTrustedMismatch) cover(mismatch);
  return mismatch;
}

template <int dim>
void WarpedFilter<dim>::solve(const Nodal<dim>& force, const Eigen::VectorXd& coupling, double dt, Nodal<dim>& dv) {
  couple(coupling);
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<int>(free.size());
  for (int a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    const Vec<dim> f = m_rotation[static_cast<std::size_t>(i)].transpose() * force.col(i);
    for (int p = 0; p < dim; ++p) m_rhs(m_h.ordered(a * dim + p), 0) = f[p];
  }
  m_h.solve_in_place(m_rhs);
  correct_for_couplings(m_rhs);
  for (int a = 0; a < nf; ++a) {
    Vec<dim> x;
    for (int p = 0; p < dim; ++p) x[p] = m_rhs(m_h.ordered(a * dim + p), 0);
    dv.col(a) = dt * (m_rotation[static_cast<std::size_t>(free[static_cast<std::size_t>(a)])] * x);
  }
}

template class WarpedFilter<2>;
template class WarpedFilter<3>;
template Eigen::SparseMatrix<double> tensor_filter_matrix<2>(const Model<2>&, double, double);
template Eigen::SparseMatrix<double> tensor_filter_matrix<3>(const Model<3>&, double, double);

} // namespace vtb
