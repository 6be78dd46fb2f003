#include "vtb/solvers/warped_filter.hh"

#include "vtb/springs/force_jacobian.hh"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {

/// The rotation R nearest to A (its polar factor) where det A > 0, by Newton's iteration
/// X <- (g X + (g X)^-T) / 2 with Higham's determinant scaling g = det(X)^(-1/3) while X is
/// far from orthogonal; X^-T = cof(X) / det(X) (the columns' cross products), so an
/// iteration is three cross products and no division but one. It converges quadratically:
/// 5-7 iterations at the strains the tensor filter trusts, against a Jacobi SVD per node that
/// made the 3D step's prepare 2.3x its solve (docs/performance.md). False (R undefined) when
/// det A <= 0 or it has not converged in 30 iterations.
bool polar_rotation(const Mat<3>& A, Mat<3>& R) {
  Mat<3> X = A;
  bool scaled = true;
  for (int it = 0; it < 30; ++it) {
    Mat<3> C;
    C.col(0) = X.col(1).cross(X.col(2));
    C.col(1) = X.col(2).cross(X.col(0));
    C.col(2) = X.col(0).cross(X.col(1));
    const double det = X.col(0).dot(C.col(0));
    if (!(det > 0) || !std::isfinite(det)) return false;
    const double g = scaled ? std::cbrt(1 / det) : 1.0;
    R = 0.5 * (g * X + C * (1 / (g * det)));
    const double change = (R - X).squaredNorm();
    if (change < 1e-30) return true; // |R| = sqrt(3): a change of 1e-15, at round-off
    scaled = change > 1e-4;          // near orthogonal, unscaled steps converge quadratically
    X = R;
  }
  return false;
}

/// The largest direction mismatch |d/|d| - t/|t|| over pairs (d, t): a spring's current
/// vector d and its rest vector turned by both ends' rotations, t = (R_i + R_j) D (their
/// mean: a smooth rotation field, bending, then leaves no mismatch, a distortion, shear,
/// which turns springs apart, does). |d/|d| - t/|t|| = 2 sin(theta / 2), theta the angle
/// between d and t: below 90 degrees the largest mismatch is the largest sin^2 theta =
/// |d x t|^2 / (|d|^2 |t|^2), scale-free in t (no rest direction to normalise) and with no
/// square root per spring (the step's cost: docs/performance.md); value() makes the mismatch
/// from it once. NaN propagates.
struct MismatchTracker {
  double worst_sin2 = 0, worst = 0;

  template <int dim> void add(const Vec<dim>& d, const Vec<dim>& t) {
    const double dd = d.squaredNorm();
    if (!(dd > 0)) return;
    const double tt = t.squaredNorm();
    if (d.dot(t) > 0) {
      double cross2;
      if constexpr (dim == 2) {
        cross2 = d.x() * t.y() - d.y() * t.x();
        cross2 *= cross2;
      } else {
        cross2 = d.cross(t).squaredNorm();
      }
      // Divided only where a new worst is found (the divider stalled the loop); NaN stays.
      if (!(cross2 <= worst_sin2 * (dd * tt))) {
        const double s2 = cross2 / (dd * tt);
        worst_sin2 = std::isnan(worst_sin2) ? worst_sin2 : s2;
      }
    } else { // 90 degrees or more (at least sqrt(2)), or not finite: rare, directly
      const double m = (d / std::sqrt(dd) - t / std::sqrt(tt)).norm();
      if (!(m <= worst)) worst = m;
    }
  }

  double value() const {
    // 2 sin(theta / 2) = sqrt(2 - 2 cos theta) = sqrt(2 sin^2 / (1 + cos)), cos = sqrt(1 - sin^2).
    const double s2 = std::min(worst_sin2, 1.0);
    const double from_sin = std::sqrt(2 * s2 / (1 + std::sqrt(1 - s2)));
    return std::isnan(worst_sin2) || std::isnan(worst) ? std::numeric_limits<double>::quiet_NaN()
                                                       : std::max(worst, from_sin);
  }
};

/// f, factorised.
const OrderedLDLT& factorised(OrderedLDLT& f) {
  if (!f.factorize()) throw std::runtime_error("filtered (tensor): H is not positive definite");
  return f;
}

} // namespace

template <int dim>
WarpedFilter<dim>::WarpedFilter(const Model<dim>& model, double dt)
    : WarpedFilter(model, dt, tensor_filter_matrix(model, dt, 0.0)) {}

template <int dim>
WarpedFilter<dim>::WarpedFilter(const Model<dim>& model, double dt, const Eigen::SparseMatrix<double>& H0)
    : m_model(model), m_h(H0, dim), m_h_blocks(factorised(m_h)),
      m_rotation(static_cast<std::size_t>(model.num_nodes()), Mat<dim>::Identity()),
      m_rhs(static_cast<Eigen::Index>(model.free_nodes.size()) * dim, 1),
      m_z(static_cast<Eigen::Index>(model.free_nodes.size()) * dim, kMaxCoupled * dim),
      m_capacitance(kMaxCoupled * dim) {
  // H(beta) = H(0) + beta (H(1) - H(0)) entry by entry: both have one pattern.
  const Eigen::SparseMatrix<double> H1 = tensor_filter_matrix(model, dt, 1.0);
  m_base.assign(m_h.values(), m_h.values() + m_h.nonzeros());
  m_transverse.assign(m_base.size(), 0.0);
  for (int c = 0; c < H0.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it0(H0, c), it1(H1, c); it0; ++it0, ++it1) {
      const int r = m_h.ordered(static_cast<int>(it0.row())), cc = m_h.ordered(c);
      if (r <= cc) m_transverse[static_cast<std::size_t>(m_h.offset(r, cc))] += it1.value() - it0.value();
    }
}

template <int dim> double WarpedFilter<dim>::direction_mismatch(const Nodal<dim>& u) const {
  const auto& net = m_model.net;
  MismatchTracker worst;
  for (int s = 0; s < net.num_springs(); ++s) {
    const auto [i, j] = net.edge[static_cast<std::size_t>(s)];
    const Vec<dim> D = net.rest.col(j) - net.rest.col(i);
    worst.add<dim>(D + u.col(j) - u.col(i),
                   (m_rotation[static_cast<std::size_t>(i)] + m_rotation[static_cast<std::size_t>(j)]) * D);
  }
  return worst.value();
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
  m_h_blocks.refresh();
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
  // A_i = sum over i's springs (x_j - x_i)(X_j - X_i)^T, gathered node by node so that the
  // sum stays in registers (scattered spring by spring, each add waited on the previous
  // one's store to the same node). In 2D the rotation needs only A00 + A11 = sum d . D and
  // A10 - A01 = sum D x d, kept in A's first column.
  for (int i = 0; i < net.num_nodes(); ++i) {
    const auto ui = u.col(i);
    const auto Xi = net.rest.col(i);
    Mat<dim> A = Mat<dim>::Zero();
    for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p) {
      const int j = net.adj_node[static_cast<std::size_t>(p)];
      const Vec<dim> D = net.rest.col(j) - Xi;
      const Vec<dim> d = D + u.col(j) - ui;
      if constexpr (dim == 2) {
        A(0, 0) += d.dot(D);
        A(1, 0) += D.x() * d.y() - D.y() * d.x();
      } else {
        A.noalias() += d * D.transpose();
      }
    }
    Mat<dim>& R = m_rotation[static_cast<std::size_t>(i)];
    if constexpr (dim == 2) {
      // The rotation nearest to A (polar part) in closed form: its angle is that of
      // (a, b) = (A00 + A11, A10 - A01), so (cos, sin) = (a, b) / |(a, b)| (no atan2).
      const double a = A(0, 0), b = A(1, 0), r2 = a * a + b * b;
      if (r2 > 0) {
        const double inv = 1 / std::sqrt(r2);
        R << a * inv, -b * inv, b * inv, a * inv;
      } else {
        R.setIdentity();
      }
    } else if (!polar_rotation(A, R)) { // an inverted or flat neighbourhood: the SVD decides
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
  m_h_blocks.solve_in_place(Eigen::Map<Nodal<dim>>(m_rhs.data(), dim, nf)); // node-ordered: tile k = rows k dim ..
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
