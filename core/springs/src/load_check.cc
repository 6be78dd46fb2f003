#include "vtb/springs/load_check.hh"

#include "vtb/springs/calibration.hh"
#include "vtb/springs/fitted_springs.hh"
#include "vtb/springs/force_jacobian.hh"

#include <Eigen/CholmodSupport>

#include <limits>

namespace vtb {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// K_ff^-1 f by CHOLMOD's supernodal Cholesky; false where K_ff is not positive definite.
bool solve(const SpMat& K, const Eigen::VectorXd& f, Eigen::VectorXd& u) {
  Eigen::CholmodSupernodalLLT<SpMat> llt(K);
  if (llt.info() != Eigen::Success) return false;
  u = llt.solve(f);
  return llt.info() == Eigen::Success && u.allFinite();
}

} // namespace

template <int dim> SpMat free_dof_block(const SpMat& K, const Problem<dim>& p) {
  std::vector<Eigen::Triplet<double>> kept;
  kept.reserve(static_cast<std::size_t>(K.nonZeros()));
  for (int col = 0; col < K.outerSize(); ++col)
    for (SpMat::InnerIterator it(K, col); it; ++it) {
      const int a = p.free_index[static_cast<std::size_t>(it.row() / dim)];
      const int b = p.free_index[static_cast<std::size_t>(it.col() / dim)];
      if (a >= 0 && b >= 0) kept.emplace_back(dim * a + it.row() % dim, dim * b + it.col() % dim, it.value());
    }
  const auto n = static_cast<Eigen::Index>(dim * p.free_nodes.size());
  SpMat out(n, n);
  out.setFromTriplets(kept.begin(), kept.end());
  return out;
}

template <int dim>
LoadCheck static_load_check(const Problem<dim>& problem, const SpringNetwork<dim>& net, const MaterialDesc& material,
                            const Yardstick* yardstick) {
  LoadCheck check;
  const int nf = static_cast<int>(problem.free_nodes.size());
  if (problem.loads.empty() || dim * nf > kLoadCheckDofs) return check;
  std::vector<int> held;
  for (int v = 0; v < problem.num_nodes(); ++v)
    if (problem.constrained[static_cast<std::size_t>(v)]) held.push_back(v);
  if (!supports_hold(problem.mesh, held)) return check;
  Nodal<dim> loads(dim, problem.num_nodes());
  problem.external_forces(std::numeric_limits<double>::infinity(), loads); // every load at its full value
  Eigen::VectorXd f(dim * nf);
  for (int a = 0; a < nf; ++a)
    f.template segment<dim>(dim * a) = loads.col(problem.free_nodes[static_cast<std::size_t>(a)]);
  if (f.squaredNorm() == 0) return check;
  const SpMat K_fem = free_dof_block(
      fem_stiffness_matrix(problem.mesh, material.young_modulus, material.poisson_ratio, material.thickness), problem);
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, problem.num_nodes());
  const SpMat K_springs = free_stiffness(net, rest, problem.free_index, nf, false);
  Eigen::VectorXd u_fem, u_springs;
  if (!solve(K_fem, f, u_fem) || !solve(K_springs, f, u_springs) || u_fem.squaredNorm() == 0) return check;
  std::optional<YardstickAnswer<dim>> continuum;
  if (yardstick && yardstick->solve<dim>()) continuum = yardstick->solve<dim>()(problem, material);
  if (!continuum || continuum->u.squaredNorm() == 0) {
    check.springs = (u_springs - u_fem).norm() / u_fem.norm();
    check.yardstick = "P1 FEM on the mesh";
    return check;
  }
  // Both answers at every node (held nodes at zero) against the continuum's at the same nodes.
  Nodal<dim> us = rest, up1 = rest;
  for (int a = 0; a < nf; ++a) {
    const int v = problem.free_nodes[static_cast<std::size_t>(a)];
    us.col(v) = u_springs.template segment<dim>(dim * a);
    up1.col(v) = u_fem.template segment<dim>(dim * a);
  }
  const double norm = continuum->u.norm();
  check.springs = (us - continuum->u).norm() / norm;
  check.mesh_fem = (up1 - continuum->u).norm() / norm;
  check.yardstick = "the continuum (" + continuum->how + ")";
  return check;
}

template Eigen::SparseMatrix<double> free_dof_block<2>(const Eigen::SparseMatrix<double>&, const Problem<2>&);
template Eigen::SparseMatrix<double> free_dof_block<3>(const Eigen::SparseMatrix<double>&, const Problem<3>&);
template LoadCheck static_load_check<2>(const Problem<2>&, const SpringNetwork<2>&, const MaterialDesc&,
                                        const Yardstick*);
template LoadCheck static_load_check<3>(const Problem<3>&, const SpringNetwork<3>&, const MaterialDesc&,
                                        const Yardstick*);

} // namespace vtb
