#include "vtb/springs/model.hh"

#include "vtb/base/input_error.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/fitted_springs.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/springs/load_pressure.hh"

#include <cstdio>
#include <limits>

namespace vtb {

template <int dim>
Model<dim> build_model(const Scene& scene, Mesh<dim> mesh, const FitProgress& progress, bool check_loads,
                       const Yardstick* yardstick) {
  Model<dim> model;
  static_cast<Problem<dim>&>(model) = build_problem<dim>(scene, std::move(mesh));
  std::vector<int> supports; // the fit trains on the body as the scene holds it
  for (int v = 0; v < model.num_nodes(); ++v)
    if (model.constrained[static_cast<std::size_t>(v)]) supports.push_back(v);
  FitTarget target; // the continuum's answers where the yardstick gives them, else P1's
  if (yardstick && yardstick->target<dim>()) target = yardstick->target<dim>()(model, scene.material);
  // springs = "auto" on a scene whose loads press deep: the fitted network with the volume per
  // node (docs/volume_term.md, "What auto builds"); else the pair springs (build_network).
  std::string springs = scene.solver.springs, deep_note;
  if (springs == "auto") {
    Nodal<dim> f = Nodal<dim>::Zero(dim, model.num_nodes());
    model.external_forces(std::numeric_limits<double>::infinity(), f);
    const double press = deepest_load_pressure<dim>(model.mesh, Eigen::Map<const Eigen::VectorXd>(f.data(), f.size()),
                                                    scene.material.young_modulus, scene.material.thickness);
    if (press >= kDeepLoadPressure && fit_affordable(model.mesh, supports).empty()) {
      springs = "fitted-nodal";
      char line[200];
      std::snprintf(line, sizeof line,
                    "springs = \"auto\" builds fitted-nodal: a load presses %.2g E, past the %.2g E at which a pair "
                    "network inverts cells",
                    press, kDeepLoadPressure);
      deep_note = line;
    }
  }
  try {
    model.net = build_network(model.mesh, scene.material, springs, supports, progress, target);
  } catch (const InputError&) { // where the volume network's fit cannot run, auto's own fallback
    if (deep_note.empty()) throw;
    springs = "auto";
    deep_note.clear();
    model.net = build_network(model.mesh, scene.material, springs, supports, progress, target);
  }
  if (!deep_note.empty()) {
    model.net.calibration_requested = "auto";
    model.net.calibration_note =
        model.net.calibration_note.empty() ? deep_note : deep_note + "; " + model.net.calibration_note;
  }
  if (check_loads) {
    const LoadCheck check = static_load_check<dim>(model, model.net, scene.material, yardstick);
    model.net.calibration_load_error = check.springs;
    model.net.mesh_fem_load_error = check.mesh_fem;
    model.net.calibration_yardstick = check.yardstick;
  }
  return model;
}

template <int dim> RunReport spring_report(const Model<dim>& model, const std::string& solver) {
  RunReport rep;
  rep.solver = solver;
  rep.dim = dim;
  rep.nodes = model.num_nodes();
  rep.springs = model.net.num_springs();
  rep.free_nodes = static_cast<int>(model.free_nodes.size());
  rep.duration = model.duration;
  rep.calibration = model.net.calibration;
  rep.calibration_requested = model.net.calibration_requested;
  rep.calibration_validation = model.net.calibration_validation;
  rep.calibration_load_error = model.net.calibration_load_error;
  rep.mesh_fem_load_error = model.net.mesh_fem_load_error;
  rep.calibration_yardstick = model.net.calibration_yardstick;
  rep.calibration_target = model.net.calibration_target;
  rep.calibration_note = model.net.calibration_note;
  rep.calibration_seconds = model.net.calibration_seconds;
  rep.calibration_cached = model.net.calibration_cached;
  rep.calibration_own_loads = model.net.calibration_own_loads;
  rep.effective_poisson_ratio = spring_poisson_ratio(dim);
  if (!model.net.volume.empty()) rep.extra.emplace_back("volume_cells", static_cast<double>(model.net.volume.size()));
  return rep;
}

template RunReport spring_report<2>(const Model<2>&, const std::string&);
template RunReport spring_report<3>(const Model<3>&, const std::string&);
template Model<2> build_model<2>(const Scene&, Mesh<2>, const FitProgress&, bool, const Yardstick*);
template Model<3> build_model<3>(const Scene&, Mesh<3>, const FitProgress&, bool, const Yardstick*);

} // namespace vtb
