#include "vtb/core/cell_fields.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtb {

template <int dim> void cell_max_principal_strain(const Mesh<dim>& mesh, const Nodal<dim>& u, std::vector<float>& out) {
  out.resize(mesh.cells.size());
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const auto& cell = mesh.cells[c];
    Mat<dim> Dm, Ds;
    for (int k = 0; k < dim; ++k) {
      const int v = cell[static_cast<std::size_t>(k) + 1];
      Dm.col(k) = mesh.points.col(v) - mesh.points.col(cell[0]);
      Ds.col(k) = Dm.col(k) + u.col(v) - u.col(cell[0]);
    }
    const Mat<dim> F = Ds * Dm.inverse();
    const Mat<dim> E = 0.5 * (F.transpose() * F - Mat<dim>::Identity());
    const Vec<dim> ev = Eigen::SelfAdjointEigenSolver<Mat<dim>>(E, Eigen::EigenvaluesOnly).eigenvalues();
    const double m = std::max(std::abs(ev.minCoeff()), std::abs(ev.maxCoeff()));
    out[c] = std::isfinite(m) ? static_cast<float>(m) : std::numeric_limits<float>::infinity();
  }
}

template <int dim> double max_small_strain(const Mesh<dim>& mesh, const Nodal<dim>& u) {
  double worst = 0;
  for (const auto& cell : mesh.cells) {
    Mat<dim> Dm, Du;
    for (int k = 0; k < dim; ++k) {
      const int v = cell[static_cast<std::size_t>(k) + 1];
      Dm.col(k) = mesh.points.col(v) - mesh.points.col(cell[0]);
      Du.col(k) = u.col(v) - u.col(cell[0]);
    }
    const Mat<dim> g = Du * Dm.inverse();
    const Mat<dim> eps = 0.5 * (g + g.transpose());
    const double m =
        Eigen::SelfAdjointEigenSolver<Mat<dim>>(eps, Eigen::EigenvaluesOnly).eigenvalues().cwiseAbs().maxCoeff();
    if (!(m <= worst)) worst = m; // propagates NaN
  }
  return worst;
}

template void cell_max_principal_strain<2>(const Mesh<2>&, const Nodal<2>&, std::vector<float>&);
template void cell_max_principal_strain<3>(const Mesh<3>&, const Nodal<3>&, std::vector<float>&);
template double max_small_strain<2>(const Mesh<2>&, const Nodal<2>&);
template double max_small_strain<3>(const Mesh<3>&, const Nodal<3>&);

} // namespace vtb
