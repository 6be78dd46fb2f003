// The volume term per cell: its rest data, forces, energy and the volume ratios a run reports.
#include "vtb/springs/cell_volumes.hh"

#include "vtb/base/input_error.hh"

#include <algorithm>
#include <numeric>
#include <string>

namespace vtb {

template <int dim>
void add_volume_forces(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>& v,
                       Nodal<dim>& f, double extra_damping_per_k) {
  Eigen::Matrix<double, dim, dim + 1> g;
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  for (int c = 0; c < cv.size(); ++c) {
    const auto& cell = cv.cell[static_cast<std::size_t>(c)];
    const double J = volume_ratio_gradients<dim>(edge_matrix<dim>(cell, x), cv.inverse_rest_det[c], g);
    double rate = 0; // dJ/dt
    for (int a = 0; a <= dim; ++a) rate += g.col(a).dot(v.col(cell[a]));
    const double k = cv.stiffness[c];
    const double s = k * (J - 1.0) + (cv.damping[c] + extra_damping_per_k * k) * rate;
    for (int a = 0; a <= dim; ++a) f.col(cell[a]) -= s * g.col(a);
  }
}

template <int dim> double volume_energy(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u) {
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  double e = 0;
  for (int c = 0; c < cv.size(); ++c) {
    const double J = edge_matrix<dim>(cv.cell[static_cast<std::size_t>(c)], x).determinant() * cv.inverse_rest_det[c];
    e += 0.5 * cv.stiffness[c] * (J - 1.0) * (J - 1.0);
  }
  return e;
}

template <int dim>
VolumeRatios volume_ratios(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                           const Nodal<dim>& u) {
  const auto X = [&](int i) -> Vec<dim> { return rest.col(i); };
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  VolumeRatios r;
  for (const auto& cell : cells) {
    const double J = edge_matrix<dim>(cell, x).determinant() / edge_matrix<dim>(cell, X).determinant();
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
  const auto X = [&](int i) -> Vec<dim> { return rest.col(i); };
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const Mat<dim> Dm = edge_matrix<dim>(cv.cell[c], X);
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
