#include "vtb/springs/spring_network.hh"

#include "vtb/springs/calibration.hh"
#include "vtb/springs/fitted_cache.hh"
#include "vtb/springs/fitted_springs.hh"

#include <algorithm>
#include <chrono>
#include <numeric>

namespace vtb {

template <int dim>
SpringNetwork<dim> build_network(const Mesh<dim>& mesh, const MaterialDesc& mat, std::string_view calibration,
                                 const std::vector<int>& supports, const FitProgress& progress,
                                 const FitTarget& target) {
  SpringNetwork<dim> net;
  net.rest = mesh.points;
  net.mass = lumped_masses(mesh, mat.density, mat.thickness);
  net.edge = unique_edges(mesh);
  net.calibration_requested = std::string(calibration);
  const auto start = std::chrono::steady_clock::now();
  if (calibration == "auto") {
    const std::string why = fit_affordable(mesh, supports);
    calibration = why.empty() ? "fitted" : "lloyd";
    if (!why.empty()) net.calibration_note = "springs = \"auto\" uses lloyd: " + why;
  }
  net.calibration = std::string(calibration);
  if (calibration == "lloyd")
    net.stiffness = lloyd_stiffness(mesh, mat.young_modulus, mat.poisson_ratio, mat.thickness);
  else if (calibration == "van-gelder")
    net.stiffness = van_gelder_stiffness(mesh, mat.young_modulus, mat.thickness);
  else if (calibration == "fitted" || calibration == "fitted-volume" || calibration == "fitted-stable" ||
           calibration == "fitted-nodal") {
    CachedFit fit;
    const bool volume = calibration != "fitted", nodal = calibration == "fitted-nodal";
    const double shear = calibration == "fitted-stable" || nodal ? kStableCellShear : 0.0;
    Eigen::VectorXd cell_k;
    try {
      net.stiffness = cached_fitted_stiffness(mesh, mat.young_modulus, mat.poisson_ratio, mat.thickness, supports, &fit,
                                              progress, target, volume ? &cell_k : nullptr, shear, nodal);
      if (volume) { // the fit's cells are in make_cell_volumes' order: their constants set after it
        const double mu = mat.young_modulus / (2 * (1 + mat.poisson_ratio));
        if (nodal) { // each cell keeps mu V_c (cell_volumes.hh), the nodes have the fit's constants
          net.volume = make_cell_volumes<dim>(mesh.cells, mesh.points, Eigen::VectorXd::Zero(mesh.num_cells()), 0.0);
          set_cell_shear(net.volume, mu, shear, mat.thickness, mat.retardation_time);
          const Eigen::VectorXd own = modulus_times_volume(net.volume, mu, mat.thickness);
          make_nodal_volumes(net.volume, mesh.num_nodes(), &own, &cell_k, mat.retardation_time);
        } else {
          net.volume = make_cell_volumes<dim>(mesh.cells, mesh.points, Eigen::VectorXd::Zero(mesh.num_cells()), 0.0);
          net.volume.stiffness = cell_k;
          net.volume.damping = mat.retardation_time * cell_k;
          if (shear > 0) set_cell_shear(net.volume, mu, shear, mat.thickness, mat.retardation_time);
        }
      }
      net.calibration_target = target.answers ? target.how : "P1 FEM on the mesh";
      net.calibration_own_loads = trains_on_own_loads(target, volume) && fit.chosen == "fitted"; // not a prior
    } catch (const InputError& e) { // auto falls back where the fit cannot run (a mesh in pieces)
      if (net.calibration_requested != "auto") throw;
      net.calibration = "lloyd";
      net.calibration_note = std::string("springs = \"auto\" uses lloyd: ") + e.what();
      net.stiffness = lloyd_stiffness(mesh, mat.young_modulus, mat.poisson_ratio, mat.thickness);
      fit.chosen = "lloyd";
      fit.validation = std::numeric_limits<double>::quiet_NaN();
    }
    net.calibration_cached = fit.hit;
    net.calibration_validation = fit.validation;
    if (fit.chosen != "fitted" && net.calibration_note.empty()) {
      net.calibration = fit.chosen;
      net.calibration_note = "the fit kept " +
                             std::string(fit.chosen == "volume" ? "the element fit (volume)" : fit.chosen) +
                             "'s constants: they answer its held-out modes better";
    }
  } else if (calibration == "volume" || calibration == "nodal-volume") {
    Eigen::VectorXd cell_k;
    net.stiffness = lloyd_volume_stiffness(mesh, mat.young_modulus, mat.poisson_ratio, mat.thickness, cell_k);
    net.volume = make_cell_volumes<dim>(mesh.cells, mesh.points, std::move(cell_k), mat.retardation_time);
    if (calibration == "nodal-volume") make_nodal_volumes(net.volume, mesh.num_nodes());
  } else
    throw InputError(
        "[solver].springs = \"" + std::string(calibration) +
        "\": must be auto, lloyd, van-gelder, fitted, volume, nodal-volume, fitted-volume, fitted-stable or "
        "fitted-nodal");
  net.calibration_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  net.damping = mat.retardation_time * net.stiffness;
  net.mass_damping = mat.mass_damping;
  const int ns = net.num_springs();
  net.rest_length.resize(ns);
  for (int s = 0; s < ns; ++s)
    net.rest_length[s] = (mesh.points.col(net.edge[static_cast<std::size_t>(s)][1]) -
                          mesh.points.col(net.edge[static_cast<std::size_t>(s)][0]))
                             .norm();

  const int n = net.num_nodes();
  std::vector<std::vector<std::pair<int, int>>> adj(static_cast<std::size_t>(n));
  for (int s = 0; s < ns; ++s) {
    const auto [i, j] = net.edge[static_cast<std::size_t>(s)];
    adj[static_cast<std::size_t>(i)].push_back({j, s});
    adj[static_cast<std::size_t>(j)].push_back({i, s});
  }
  net.adj_ptr.assign(1, 0);
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    for (const auto& [j, s] : a) {
      net.adj_node.push_back(j);
      net.adj_spring.push_back(s);
    }
    net.adj_ptr.push_back(static_cast<int>(net.adj_node.size()));
  }
  return net;
}

template <int dim> double max_strain(const SpringNetwork<dim>& net, const Nodal<dim>& u) {
  double m = 0;
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const double l = (net.rest.col(j) + u.col(j) - net.rest.col(i) - u.col(i)).norm();
    const double strain = std::abs(l / net.rest_length[s] - 1.0);
    if (!(strain <= m)) m = strain; // propagates NaN
  }
  return m;
}

template <int dim> double elastic_energy(const SpringNetwork<dim>& net, const Nodal<dim>& u) {
  double e = 0;
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const double l = (net.rest.col(j) + u.col(j) - net.rest.col(i) - u.col(i)).norm();
    e += 0.5 * net.stiffness[s] * (l - net.rest_length[s]) * (l - net.rest_length[s]);
  }
  return e + volume_energy(net.volume, net.rest, u);
}

template <int dim> double kinetic_energy(const SpringNetwork<dim>& net, const Nodal<dim>& v) {
  return 0.5 * (v.colwise().squaredNorm().transpose().array() * net.mass.array()).sum();
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template SpringNetwork<D> build_network<D>(const Mesh<D>&, const MaterialDesc&, std::string_view,                    \
                                             const std::vector<int>&, const FitProgress&, const FitTarget&);           \
  template double max_strain<D>(const SpringNetwork<D>&, const Nodal<D>&);                                             \
  template double elastic_energy<D>(const SpringNetwork<D>&, const Nodal<D>&);                                         \
  template double kinetic_energy<D>(const SpringNetwork<D>&, const Nodal<D>&);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

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

template void cell_spring_force<2>(const Mesh<2>&, const SpringNetwork<2>&, const Nodal<2>&, std::vector<double>&);
template void cell_spring_force<3>(const Mesh<3>&, const SpringNetwork<3>&, const Nodal<3>&, std::vector<double>&);

} // namespace vtb
