#include "fit_training.hh"

#include "vtb/springs/calibration.hh"

#include <algorithm>
#include <cmath>
#include <random>

namespace vtb {
namespace fit {
namespace {

/// Rigid motions of the mesh: dim translations and the rotations about the centroid.
/// (The lowest modes below take R with no columns for a supported body.)
template <int dim> MatrixXd rigid_modes(const Mesh<dim>& mesh) {
  const int n = mesh.num_nodes();
  constexpr int r = dim == 2 ? 3 : 6;
  MatrixXd R = MatrixXd::Zero(dim * n, r);
  const Vec<dim> c = mesh.points.rowwise().mean();
  for (int v = 0; v < n; ++v) {
    const Vec<dim> x = mesh.points.col(v) - c;
    for (int i = 0; i < dim; ++i) R(dim * v + i, i) = 1;
    if constexpr (dim == 2) {
      R(2 * v, 2) = -x[1];
      R(2 * v + 1, 2) = x[0];
    } else {
      for (int k = 0; k < 3; ++k) {
        const Vec<3> w = Vec<3>::Unit(k).cross(x);
        R.block<3, 1>(3 * v, 3 + k) = w;
      }
    }
  }
  return R;
}

/// A statically determinate set of pinned dofs that removes exactly the rigid motions: node a
/// (the first) entirely; at node b (farthest from a) the components across ab; in 3D one
/// component at node c (farthest from the line ab) against the rotation about ab. A linear
/// static answer with these pins is the free body's answer plus a rigid motion.
template <int dim> std::vector<int> pinned_dofs(const Mesh<dim>& mesh) {
  const int n = mesh.num_nodes();
  const Vec<dim> xa = mesh.points.col(0);
  Eigen::Index b = 0;
  (mesh.points.colwise() - xa).colwise().squaredNorm().maxCoeff(&b);
  const Vec<dim> d = mesh.points.col(b) - xa;
  std::vector<int> pins;
  for (int i = 0; i < dim; ++i) pins.push_back(i);
  Eigen::Index p = 0;
  d.cwiseAbs().maxCoeff(&p);
  for (int i = 0; i < dim; ++i)
    if (i != p) pins.push_back(dim * static_cast<int>(b) + i);
  if constexpr (dim == 3) {
    const Vec<3> axis = d.normalized();
    double best = -1;
    int c = 0;
    for (int v = 0; v < n; ++v) {
      const double dist = axis.cross(Vec<3>(mesh.points.col(v) - xa)).norm();
      if (dist > best) best = dist, c = v;
    }
    const Vec<3> w = axis.cross(Vec<3>(mesh.points.col(c) - xa));
    Eigen::Index q = 0;
    w.cwiseAbs().maxCoeff(&q);
    pins.push_back(3 * c + static_cast<int>(q));
  }
  return pins;
}

/// How far the subspace iteration converges the modes' eigenvalues (relative change per
/// iteration). A training pair (F = K_fem phi, T = phi) is the FEM's exact answer whether or
/// not phi is an exact eigenvector, so the modes need only be low-mode shaped: at 1e-8 the
/// 10k-node slab's modes took 10 of its fit's 50 s (docs/fidelity.md).
constexpr double kModeTolerance = 1e-4;

/// The lowest `count` non-rigid modes of K phi = lambda M phi (M diagonal) by subspace
/// iteration with Rayleigh-Ritz: X <- Pi_M K^+ M X, Pi_M the M-orthogonal projector off the
/// rigid modes (K^+ through the pinned solve: the pins add only rigid motions, which Pi_M
/// removes). Columns M-orthonormal, ascending.
MatrixXd lowest_modes(const SpMat& K, PinnedSolver& solver, const VectorXd& mass, const MatrixXd& R, int count,
                      VectorXd& eigenvalues, const FitProgress& progress) {
  const Eigen::Index N = K.rows();
  const int block = count + std::max(8, count / 2);
  const MatrixXd RtMR = R.transpose() * mass.asDiagonal() * R;
  const Eigen::LLT<MatrixXd> rtmr(RtMR);
  auto project = [&](MatrixXd& Y) {
    if (R.cols() > 0) Y -= R * rtmr.solve(R.transpose() * (mass.asDiagonal() * Y));
  };
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  MatrixXd X(N, block);
  for (Eigen::Index j = 0; j < X.cols(); ++j)
    for (Eigen::Index i = 0; i < N; ++i) X(i, j) = uni(rng);
  project(X);
  VectorXd previous = VectorXd::Constant(count, -1.0);
  constexpr int kMaxIterations = 300;
  if (progress) progress("modes", 0, kMaxIterations);
  for (int it = 0; it < kMaxIterations; ++it) {
    MatrixXd Y = solver.solve(mass.asDiagonal() * X);
    project(Y);
    MatrixXd Kr = Y.transpose() * (K * Y), Mr = Y.transpose() * mass.asDiagonal() * Y;
    Kr = 0.5 * (Kr + Kr.transpose()).eval();
    Mr = 0.5 * (Mr + Mr.transpose()).eval();
    const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> es(Kr, Mr);
    X = Y * es.eigenvectors();
    const VectorXd lambda = es.eigenvalues().head(count);
    const bool converged = ((lambda - previous).cwiseAbs().array() <= kModeTolerance * lambda.array()).all();
    previous = lambda;
    if (progress) progress("modes", it + 1, kMaxIterations);
    if (converged) break;
  }
  eigenvalues = previous;
  return X.leftCols(count);
}

/// The FEM's answers to its own uniform stress states: for each unit strain e_j (3 in 2D, 6
/// in 3D) the affine field u_j = e_j (x - centroid), whose loads K u_j are the boundary
/// tractions of a uniform stress, answered with the body's supports (or pins, then projected
/// off the rigid motions: the free body's answer is u_j itself), scaled so that each load has
/// `load_size`, the training modes' load size (loads of one size, as for the modes). These are the
/// loads of a tension, shear or compression test, which the low modes of a slender or
/// clamped body barely contain (a clamped strip's first axial mode is its third, at 240 times
/// the first eigenvalue).
template <int dim>
MatrixXd uniform_stress_answers(const Mesh<dim>& mesh, const SpMat& K, const PinnedSolver& fem, const MatrixXd& Q,
                                double load_size) {
  constexpr int count = dim * (dim + 1) / 2;
  const int n = mesh.num_nodes();
  const Vec<dim> c = mesh.points.rowwise().mean();
  MatrixXd U = MatrixXd::Zero(dim * n, count);
  int j = 0;
  for (int a = 0; a < dim; ++a)
    for (int b = a; b < dim; ++b, ++j)
      for (int v = 0; v < n; ++v) {
        const Vec<dim> x = mesh.points.col(v) - c;
        U(dim * v + a, j) += (a == b ? 1.0 : 0.5) * x[b];
        if (a != b) U(dim * v + b, j) += 0.5 * x[a];
      }
  MatrixXd T = fem.solve(K * U);
  T -= Q * (Q.transpose() * T);
  const MatrixXd F = K * T;
  for (Eigen::Index col = 0; col < T.cols(); ++col) T.col(col) *= load_size / F.col(col).norm();
  return T;
}

/// The scene's own loads and the target's answers to them, appended to the training pairs:
/// each scaled so that its load has `load_size` (the modes') times FitOptions::own_load. The
/// held rows of a load are the supports' reactions, not applied forces. Nothing is appended
/// where the target does not answer.
void append_own_loads(Training& tr, const FitOptions& o, double E, double nu, double thickness, double load_size) {
  const MatrixXd& loads = o.target.own_loads;
  if (!(o.own_load > 0) || loads.cols() == 0 || !o.target.own_answers) return;
  MatrixXd f = loads;
  for (const int d : tr.pins) f.row(d).setZero();
  MatrixXd u = o.target.own_answers(E, nu, thickness);
  if (u.rows() != f.rows() || u.cols() != f.cols() || !u.allFinite()) return;
  for (const int d : tr.pins) u.row(d).setZero();
  for (Eigen::Index c = 0; c < f.cols(); ++c) {
    const double size = f.col(c).norm();
    if (!(size > 0) || !(u.col(c).norm() > 0)) continue;
    const double s = o.own_load * load_size / size;
    tr.F.conservativeResize(Eigen::NoChange, tr.F.cols() + 1);
    tr.T.conservativeResize(Eigen::NoChange, tr.T.cols() + 1);
    tr.F.rightCols(1) = s * f.col(c);
    tr.T.rightCols(1) = s * u.col(c);
  }
}

} // namespace

template <int dim>
Training training_set(const Mesh<dim>& mesh, double E, double nu, double thickness, int modes, const FitOptions& o) {
  const int n = mesh.num_nodes(), N = dim * n;
  Training tr;
  const SpMat K = fem_stiffness_matrix(mesh, E, nu, thickness);
  tr.supported = supports_hold(mesh, o.supports);
  if (tr.supported) {
    for (const int v : o.supports)
      for (int i = 0; i < dim; ++i) tr.pins.push_back(dim * v + i);
  } else {
    tr.pins = pinned_dofs(mesh);
  }
  PinnedSolver fem_solver(N, tr.pins);
  {
    SpMat held = K; // the solver sets the pins' rows in its matrix; K serves the loads below
    fem_solver.factorize(held);
  }
  VectorXd mass(N);
  const VectorXd m_nodes = lumped_masses(mesh, 1.0, thickness);
  for (int v = 0; v < n; ++v) mass.template segment<dim>(dim * v).setConstant(m_nodes[v]);
  const MatrixXd R = tr.supported ? MatrixXd(N, 0) : rigid_modes(mesh);
  tr.Q = tr.supported ? MatrixXd(N, 0)
                      : MatrixXd(Eigen::HouseholderQR<MatrixXd>(R).householderQ() * MatrixXd::Identity(N, R.cols()));
  // modes to train on and, every holdout-th, one more held out.
  const int total = o.holdout > 1 ? modes + modes / (o.holdout - 1) : modes;
  VectorXd lambda;
  MatrixXd all = lowest_modes(K, fem_solver, mass, R, total, lambda, o.progress);
  all -= tr.Q * (tr.Q.transpose() * all);
  all.colwise().normalize();
  for (int m = 0; m < total; ++m) all.col(m) *= std::pow(lambda[0] / lambda[m], o.weighting);
  const int held = total - modes;
  const MatrixXd stress =
      tr.supported && o.uniform_stress > 0
          ? MatrixXd(uniform_stress_answers(mesh, K, fem_solver, tr.Q, (K * all.col(0)).norm()) * o.uniform_stress)
          : MatrixXd(N, 0);
  tr.T.resize(N, modes + stress.cols());
  tr.Tv.resize(N, held);
  for (int m = 0, a = 0, b = 0; m < total; ++m)
    if (held > 0 && m % o.holdout == o.holdout - 1 && b < held)
      tr.Tv.col(b++) = all.col(m);
    else
      tr.T.col(a++) = all.col(m);
  tr.T.rightCols(stress.cols()) = stress;
  tr.F = K * tr.T;
  tr.Fv = K * tr.Tv;
  if (tr.supported && o.target.answers) {
    // The same loads, answered by the target instead of P1 (which answers them with T itself);
    // the held rows of a load are the supports' reactions, not applied forces.
    MatrixXd loads(N, tr.F.cols() + tr.Fv.cols());
    loads << tr.F, tr.Fv;
    for (const int d : tr.pins) loads.row(d).setZero();
    const MatrixXd U = o.target.answers(loads, E, nu, thickness);
    if (U.rows() == N && U.cols() == loads.cols() && U.allFinite()) {
      tr.T = U.leftCols(tr.F.cols());
      tr.Tv = U.rightCols(tr.Fv.cols());
      for (const int d : tr.pins) tr.T.row(d).setZero(), tr.Tv.row(d).setZero();
      append_own_loads(tr, o, E, nu, thickness, (K * all.col(0)).norm());
    }
  }
  return tr;
}

template Training training_set<2>(const Mesh<2>&, double, double, double, int, const FitOptions&);
template Training training_set<3>(const Mesh<3>&, double, double, double, int, const FitOptions&);

} // namespace fit

using fit::MatrixXd;
using fit::rigid_modes;

template <int dim> bool supports_hold(const Mesh<dim>& mesh, const std::vector<int>& supports) {
  if (supports.empty()) return false;
  const MatrixXd R = rigid_modes(mesh);
  MatrixXd Rs(dim * static_cast<Eigen::Index>(supports.size()), R.cols());
  for (std::size_t a = 0; a < supports.size(); ++a)
    Rs.middleRows(dim * static_cast<Eigen::Index>(a), dim) = R.middleRows(dim * supports[a], dim);
  Eigen::ColPivHouseholderQR<MatrixXd> qr(Rs);
  qr.setThreshold(1e-8);
  return qr.rank() == R.cols();
}

template <int dim> int fit_dofs_needed(const FitOptions& options) {
  const int modes = options.modes > 0 ? options.modes : (dim == 2 ? 16 : 24);
  const int total = options.holdout > 1 ? modes + modes / (options.holdout - 1) : modes;
  return total + std::max(8, total / 2);
}

template <int dim> int fit_pinned_dofs(const Mesh<dim>& mesh, const std::vector<int>& supports) {
  return supports_hold(mesh, supports) ? dim * static_cast<int>(supports.size()) : (dim == 2 ? 3 : 6);
}

template <int dim> std::string fit_affordable(const Mesh<dim>& mesh, const std::vector<int>& supports) {
  const int n = mesh.num_nodes(), budget = dim == 2 ? kAutoFitNodes2D : kAutoFitNodes3D;
  if (n > budget)
    return "a fit of " + std::to_string(n) + " nodes is beyond auto's budget (" + std::to_string(budget) + " in " +
           std::to_string(dim) + "D; springs = \"fitted\" fits anyway)";
  if (dim * n - fit_pinned_dofs(mesh, supports) < fit_dofs_needed<dim>())
    return "the mesh is too small to fit (" + std::to_string(n) + " nodes)";
  return {};
}

template bool supports_hold<2>(const Mesh<2>&, const std::vector<int>&);
template bool supports_hold<3>(const Mesh<3>&, const std::vector<int>&);
template int fit_dofs_needed<2>(const FitOptions&);
template int fit_dofs_needed<3>(const FitOptions&);
template int fit_pinned_dofs<2>(const Mesh<2>&, const std::vector<int>&);
template int fit_pinned_dofs<3>(const Mesh<3>&, const std::vector<int>&);
template std::string fit_affordable<2>(const Mesh<2>&, const std::vector<int>&);
template std::string fit_affordable<3>(const Mesh<3>&, const std::vector<int>&);

} // namespace vtb
