#pragma once
// Linear static answers of a network and of P1 FEM on a clamped mesh (the fit tests' held-out
// cases: test_fitted_springs.cc, test_fitted_volume.cc).
#include "vtb/springs/calibration.hh"
#include "vtb/springs/cell_volumes.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/SparseCholesky>

#include <vector>

namespace vtb::test {

using SpMat = Eigen::SparseMatrix<double>;

/// The network's rest stiffness with spring constants k (per unique edge) and, when given, a
/// volume term with the cells' k_c (make_cell_volumes' order, as fitted_stiffness gives them).
template <int dim>
SpMat network_matrix(const Mesh<dim>& mesh, const Eigen::VectorXd& k, const Eigen::VectorXd* cell_k = nullptr) {
  MaterialDesc mat;
  SpringNetwork<dim> net = build_network(mesh, mat, "van-gelder");
  net.stiffness = k;
  net.damping.setZero();
  if (cell_k) {
    net.volume = make_cell_volumes<dim>(mesh.cells, mesh.points, Eigen::VectorXd::Zero(mesh.num_cells()), 0.0);
    net.volume.stiffness = *cell_k;
  }
  const Nodal<dim> zero = Nodal<dim>::Zero(dim, mesh.num_nodes());
  return -force_jacobians<dim>(net, zero, false).K;
}

/// Linear static answer of K u = f with the nodes where `fixed` is true clamped.
inline Eigen::VectorXd clamped_solve(const SpMat& K, const Eigen::VectorXd& f, const std::vector<bool>& fixed,
                                     int dim) {
  std::vector<int> index(fixed.size(), -1);
  int nf = 0;
  for (std::size_t v = 0; v < fixed.size(); ++v)
    if (!fixed[v]) index[v] = nf++;
  std::vector<Eigen::Triplet<double>> kept;
  for (int c = 0; c < K.outerSize(); ++c)
    for (SpMat::InnerIterator it(K, c); it; ++it) {
      const int r = index[static_cast<std::size_t>(it.row() / dim)],
                q = index[static_cast<std::size_t>(it.col() / dim)];
      if (r >= 0 && q >= 0) kept.emplace_back(dim * r + it.row() % dim, dim * q + it.col() % dim, it.value());
    }
  SpMat Kff(dim * nf, dim * nf);
  Kff.setFromTriplets(kept.begin(), kept.end());
  Eigen::VectorXd rhs(dim * nf), u = Eigen::VectorXd::Zero(f.size());
  for (std::size_t v = 0; v < fixed.size(); ++v)
    if (index[v] >= 0) rhs.segment(dim * index[v], dim) = f.segment(dim * static_cast<Eigen::Index>(v), dim);
  const Eigen::VectorXd uf = Eigen::SimplicialLDLT<SpMat>(Kff).solve(rhs);
  for (std::size_t v = 0; v < fixed.size(); ++v)
    if (index[v] >= 0) u.segment(dim * static_cast<Eigen::Index>(v), dim) = uf.segment(dim * index[v], dim);
  return u;
}

/// The relative L2 error, over all nodes, of the network's clamped static answer to f against
/// P1 FEM's on the same mesh (plane stress with thickness t in 2D).
template <int dim>
double static_error(const Mesh<dim>& mesh, const Eigen::VectorXd& k, const Eigen::VectorXd* cell_k, double E, double nu,
                    double t, const std::vector<bool>& fixed, const Eigen::VectorXd& f) {
  const Eigen::VectorXd ufem = clamped_solve(fem_stiffness_matrix(mesh, E, nu, t), f, fixed, dim);
  const Eigen::VectorXd us = clamped_solve(network_matrix(mesh, k, cell_k), f, fixed, dim);
  return (us - ufem).norm() / ufem.norm();
}

} // namespace vtb::test
