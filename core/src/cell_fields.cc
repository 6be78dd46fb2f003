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

template <int dim>
void cell_spring_force(const Mesh<dim>& mesh, const SpringNetwork<dim>& net, const Nodal<dim>& u,
                       std::vector<double>& out) {
  out.assign(mesh.cells.size(), 0.0);
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const auto& cell = mesh.cells[c];
    int n = 0;
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b) {
        const std::array<int, 2> e = {std::min(cell[static_cast<std::size_t>(a)], cell[static_cast<std::size_t>(b)]),
                                      std::max(cell[static_cast<std::size_t>(a)], cell[static_cast<std::size_t>(b)])};
        const auto it = std::lower_bound(net.edge.begin(), net.edge.end(), e);
        if (it == net.edge.end() || *it != e) continue;
        const auto s = static_cast<Eigen::Index>(it - net.edge.begin());
        const double l = (net.rest.col(e[1]) + u.col(e[1]) - net.rest.col(e[0]) - u.col(e[0])).norm();
        out[c] += net.stiffness[s] * (l - net.rest_length[s]);
        ++n;
      }
    if (n > 0) out[c] /= n;
  }
}

template void cell_max_principal_strain<2>(const Mesh<2>&, const Nodal<2>&, std::vector<float>&);
template void cell_max_principal_strain<3>(const Mesh<3>&, const Nodal<3>&, std::vector<float>&);
template double max_small_strain<2>(const Mesh<2>&, const Nodal<2>&);
template double max_small_strain<3>(const Mesh<3>&, const Nodal<3>&);
template void cell_spring_force<2>(const Mesh<2>&, const SpringNetwork<2>&, const Nodal<2>&, std::vector<double>&);
template void cell_spring_force<3>(const Mesh<3>&, const SpringNetwork<3>&, const Nodal<3>&, std::vector<double>&);

} // namespace vtb
