// The volume term per cell: its rest data, forces, energy and the volume ratios a run reports.
#include "vtb/springs/cell_volumes.hh"

#include "vtb/base/input_error.hh"

#include <algorithm>
#include <numeric>
#include <string>

namespace vtb {
namespace {

template <int dim>
Eigen::Matrix<double, dim, dim + 1> cell_positions(const std::array<int, dim + 1>& cell, const Nodal<dim>& rest,
                                                   const Nodal<dim>& u) {
  Eigen::Matrix<double, dim, dim + 1> x;
  for (int a = 0; a <= dim; ++a) x.col(a) = rest.col(cell[a]) + u.col(cell[a]);
  return x;
}

template <int dim> double ratio(const Mat<dim>& rest_inverse, const Eigen::Matrix<double, dim, dim + 1>& x) {
  Mat<dim> Ds;
  for (int k = 0; k < dim; ++k) Ds.col(k) = x.col(k + 1) - x.col(0);
  return (Ds * rest_inverse).determinant();
}

} // namespace

template <int dim>
void add_volume_forces(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>& v,
                       Nodal<dim>& f, double extra_damping_per_k) {
  // With F = D_s D_m^-1: J = det(D_s) / det(D_m), and the gradients dJ/dx_a (a >= 1), the
  // columns of cof(F) D_m^-T = cof(D_s) cof(D_m^-1) D_m^-T, are those of cof(D_s) / det(D_m):
  // the cross products of the cell's edge vectors now, no rest matrix per cell.
  for (int c = 0; c < cv.size(); ++c) {
    const auto& cell = cv.cell[static_cast<std::size_t>(c)];
    const Vec<dim> x0 = rest.col(cell[0]) + u.col(cell[0]);
    Mat<dim> Ds, g; // g: dJ/dx_1 .. dJ/dx_dim
    for (int k = 0; k < dim; ++k) Ds.col(k) = rest.col(cell[k + 1]) + u.col(cell[k + 1]) - x0;
    double det;
    if constexpr (dim == 2) {
      g << Ds(1, 1), -Ds(1, 0), -Ds(0, 1), Ds(0, 0);
      det = Ds(0, 0) * Ds(1, 1) - Ds(0, 1) * Ds(1, 0);
    } else {
      g.col(0) = Ds.col(1).cross(Ds.col(2));
      g.col(1) = Ds.col(2).cross(Ds.col(0));
      g.col(2) = Ds.col(0).cross(Ds.col(1));
      det = Ds.col(0).dot(g.col(0));
    }
    const double inv = cv.inverse_rest_det[c];
    g *= inv;
    const Vec<dim> g0 = -g.rowwise().sum();
    double rate = g0.dot(v.col(cell[0])); // dJ/dt
    for (int a = 1; a <= dim; ++a) rate += g.col(a - 1).dot(v.col(cell[a]));
    const double k = cv.stiffness[c];
    const double s = k * (det * inv - 1.0) + (cv.damping[c] + extra_damping_per_k * k) * rate;
    f.col(cell[0]) -= s * g0;
    for (int a = 1; a <= dim; ++a) f.col(cell[a]) -= s * g.col(a - 1);
  }
}

template <int dim> double volume_energy(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u) {
  double e = 0;
  for (int c = 0; c < cv.size(); ++c) {
    const double J = ratio<dim>(cv.rest_inverse[static_cast<std::size_t>(c)],
                                cell_positions<dim>(cv.cell[static_cast<std::size_t>(c)], rest, u));
    e += 0.5 * cv.stiffness[c] * (J - 1.0) * (J - 1.0);
  }
  return e;
}

template <int dim>
VolumeRatios volume_ratios(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                           const Nodal<dim>& u) {
  VolumeRatios r;
  for (const auto& cell : cells) {
    Mat<dim> Dm, Ds;
    for (int k = 0; k < dim; ++k) {
      Dm.col(k) = rest.col(cell[k + 1]) - rest.col(cell[0]);
      Ds.col(k) = rest.col(cell[k + 1]) + u.col(cell[k + 1]) - rest.col(cell[0]) - u.col(cell[0]);
    }
    const double J = Ds.determinant() / Dm.determinant();
    if (!(J > 0)) ++r.inverted; // NaN counts as inverted
    if (!(J >= r.min_ratio)) r.min_ratio = J;
  }
  return r;
}

template <int dim>
CellVolumes<dim> make_cell_volumes(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                                   Eigen::VectorXd stiffness, double retardation_time) {
  CellVolumes<dim> cv;
  // In the order of their lowest node (the springs run in their first node's order): the force
  // pass then walks the nodes' columns nearly in order instead of a mesher's cell order.
  std::vector<std::size_t> order(cells.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto low = [&](std::size_t c) { return *std::min_element(cells[c].begin(), cells[c].end()); };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return low(a) < low(b); });
  Eigen::VectorXd sorted(stiffness.size());
  for (std::size_t c = 0; c < order.size(); ++c) {
    cv.cell.push_back(cells[order[c]]);
    sorted[static_cast<Eigen::Index>(c)] = stiffness[static_cast<Eigen::Index>(order[c])];
  }
  stiffness = std::move(sorted);
  cv.rest_inverse.resize(cells.size());
  cv.inverse_rest_det.resize(static_cast<Eigen::Index>(cells.size()));
  for (std::size_t c = 0; c < cells.size(); ++c) {
    Mat<dim> Dm;
    for (int k = 0; k < dim; ++k) Dm.col(k) = rest.col(cv.cell[c][k + 1]) - rest.col(cv.cell[c][0]);
    if (!(std::abs(Dm.determinant()) > 0))
      throw InputError("cell " + std::to_string(order[c]) + ": zero volume, the volume term needs a rest shape");
    cv.rest_inverse[c] = Dm.inverse();
    cv.inverse_rest_det[static_cast<Eigen::Index>(c)] = 1.0 / Dm.determinant();
  }
  cv.damping = retardation_time * stiffness;
  cv.stiffness = std::move(stiffness);
  return cv;
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template void add_volume_forces<D>(const CellVolumes<D>&, const Nodal<D>&, const Nodal<D>&, const Nodal<D>&,         \
                                     Nodal<D>&, double);                                                               \
  template double volume_energy<D>(const CellVolumes<D>&, const Nodal<D>&, const Nodal<D>&);                           \
  template VolumeRatios volume_ratios<D>(const std::vector<std::array<int, D + 1>>&, const Nodal<D>&,                  \
                                         const Nodal<D>&);                                                             \
  template CellVolumes<D> make_cell_volumes<D>(const std::vector<std::array<int, D + 1>>&, const Nodal<D>&,            \
                                               Eigen::VectorXd, double);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

} // namespace vtb
