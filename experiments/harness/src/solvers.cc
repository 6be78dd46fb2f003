#include "vtb/harness/solvers.hh"

#include "vtb/core/explicit_euler.hh"
#include "vtb/fem/kelvin_voigt.hh"

#include <algorithm>
#include <cmath>

namespace vtb::harness {

bool known_solver(const std::string& n) {
  static const char* names[] = {"explicit", "filtered", "filtered-full", "filtered-neighbors", "implicit-euler",
                                "cvode",    "fem"};
  return std::find(std::begin(names), std::end(names), n) != std::end(names);
}

template <int dim>
RunReport run_solver(const Scene& scene, const Model<dim>& model, const std::string& solver, double dt,
                     Trajectory<dim>& out) {
  if (!known_solver(solver))
    throw InputError("unknown solver \"" + solver +
                     "\": use explicit, filtered, filtered-full, filtered-neighbors, implicit-euler, cvode or fem");
  const double step = dt > 0 ? dt : scene.solver.dt;
  if (solver == "fem") {
    fem::FemOptions o = fem::options_from(scene.solver);
    o.dt = step;
    o.static_solve = false;
    return fem::simulate<dim>(model, scene.material, o, out, true);
  }
  IntegratorOptions o = integrator_options(scene.solver);
  o.kind = solver.rfind("filtered", 0) == 0 ? "filtered" : solver;
  if (solver == "filtered-full") o.filter = "full";
  if (solver == "filtered-neighbors") o.filter = "neighbors";
  o.dt = step;
  if (solver == "explicit" && dt <= 0) {
    // Half the predicted limit, rounded down so that samples fall on steps like the others'.
    const double tau = model.net.stiffness.size() ? model.net.damping[0] / model.net.stiffness[0] : 0.0;
    const double limit = 0.5 * explicit_critical_dt(max_omega_squared(model, false), tau, model.net.mass_damping);
    if (limit < step) o.dt = model.output_interval / std::ceil(model.output_interval / limit);
  }
  RunReport r = simulate(model, o, out, true);
  if (solver != o.kind) r.solver = solver;
  return r;
}

template RunReport run_solver<2>(const Scene&, const Model<2>&, const std::string&, double, Trajectory<2>&);
template RunReport run_solver<3>(const Scene&, const Model<3>&, const std::string&, double, Trajectory<3>&);

} // namespace vtb::harness
