#include "vtb/harness/solvers.hh"
#include "vtb/harness/bullet.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/base/input_error.hh"
#include "vtb/fem/continuum.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtb::harness {

template <int dim>
RunReport run_solver(const Scene& scene, const Model<dim>& model, const std::string& solver, double dt,
                     Trajectory<dim>& out) {
  const solvers::Entry& entry = solvers::find(solver);
  const double step = dt > 0 ? dt : scene.solver.dt;
  if (solver == solvers::kBullet) return run_bullet(scene, model, step, out); // a peer library
  if (!entry.springs) { // the continuum reference (reference_fem), the registry's one non-spring entry
    fem::FemOptions o = fem::options_from(scene.solver);
    o.dt = step;
    o.static_solve = false;
    return fem::simulate<dim>(model, scene.material, o, out, true);
  }
  IntegratorOptions o = solvers::integrator_options(entry, scene.solver);
  o.dt = step;
  if (solver == solvers::kExplicit && dt <= 0) {
    // Half the predicted limit, rounded down so that samples fall on steps like the others'.
    const double tau = model.net.stiffness.size() ? model.net.damping[0] / model.net.stiffness[0] : 0.0;
    const double limit = 0.5 * explicit_critical_dt(max_omega_squared(model, false), tau, model.net.mass_damping);
    if (limit < step) o.dt = model.output_interval / std::ceil(model.output_interval / limit);
  }
  RunReport r = simulate(model, o, out, true);
  if (solver != o.kind) r.solver = solver;
  return r;
}

namespace {
template <int dim> YardstickSolve<dim> continuum_solve(KeptLadders* keep) {
  return [keep](const Problem<dim>& problem, const MaterialDesc& material) -> std::optional<YardstickAnswer<dim>> {
    auto answer = fem::continuum_static<dim>(problem, material);
    if (keep) {
      keep->get<dim>() = answer;
      keep->nodes = problem.num_nodes();
      keep->young_modulus = material.young_modulus;
      keep->poisson_ratio = material.poisson_ratio;
      keep->thickness = material.thickness;
    }
    if (!answer) return std::nullopt;
    return YardstickAnswer<dim>{std::move(answer->u), answer->how};
  };
}
/// The version of the continuum's training answers in the fit cache's key: a change to the
/// ladder or its budget makes new fits.
constexpr const char* kTargetKey = "continuum-p2-ladder-2";

template <int dim> FitTargetFor<dim> continuum_target() {
  return [](const Problem<dim>& problem, const MaterialDesc&) {
    FitTarget t;
    const long dofs = fem::continuum_first_dofs(problem.mesh), budget = fem::continuum_budget(dim);
    // P2 on the mesh itself up to kContinuumFitDofs3D in 3D; refinements within the budget.
    const long first = dim == 3 ? std::max(budget, fem::kContinuumFitDofs3D) : budget;
    if (dofs > first) {
      t.how = "P1 FEM on the mesh: the continuum's P2 would need " + std::to_string(dofs) +
              " dofs, above the budget of " + std::to_string(first);
      return t;
    }
    fem::ContinuumOptions options;
    options.max_dofs = std::max(budget, dofs);
    t.key = kTargetKey;
    t.how = dofs > budget ? "the continuum (P2 on the mesh, " + std::to_string(dofs) + " dofs, unrefined)"
                          : "the continuum (P2 refined until a refinement moves the answers by less than 1 %, within " +
                                std::to_string(budget) + " dofs)";
    t.answers = [p = problem, options](const Eigen::MatrixXd& F, double E, double nu, double thickness) {
      const auto a = fem::continuum_answers<dim>(p, MaterialDesc{E, nu, 1.0, thickness, 0.0, 0.0}, F, options);
      return a ? a->u : Eigen::MatrixXd();
    };
    // The scene's own loads, every one at its full value (the load check's static problem),
    // and the continuum's answer to them as the scene applies them (a disc as a traction).
    Nodal<dim> f = Nodal<dim>::Zero(dim, problem.num_nodes());
    problem.external_forces(std::numeric_limits<double>::infinity(), f);
    if (!problem.loads.empty() && f.squaredNorm() > 0) {
      t.own_loads = Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
      t.own_answers = [p = problem, options](double E, double nu, double thickness) {
        const auto a = fem::continuum_static<dim>(p, MaterialDesc{E, nu, 1.0, thickness, 0.0, 0.0}, options);
        return a ? Eigen::MatrixXd(Eigen::Map<const Eigen::VectorXd>(a->u.data(), a->u.size())) : Eigen::MatrixXd();
      };
    }
    return t;
  };
}
} // namespace

Yardstick continuum_yardstick(KeptLadders* keep) {
  return {continuum_solve<2>(keep), continuum_solve<3>(keep), continuum_target<2>(), continuum_target<3>()};
}

template <int dim>
std::optional<fem::ContinuumAnswer<dim>> static_ladder(const Problem<dim>& problem, const MaterialDesc& material,
                                                       const fem::ContinuumOptions& options, KeptLadders* kept,
                                                       bool* reused) {
  const fem::ContinuumOptions plain;
  const bool drives =
      std::any_of(problem.supports.begin(), problem.supports.end(), [](const Support<dim>& s) { return s.driven; });
  const bool same = kept && kept->get<dim>() && kept->nodes == problem.num_nodes() &&
                    kept->young_modulus == material.young_modulus && kept->poisson_ratio == material.poisson_ratio &&
                    kept->thickness == material.thickness && options.tolerance == plain.tolerance &&
                    options.max_dofs == plain.max_dofs && options.max_refinements == plain.max_refinements &&
                    (!options.drives_displaced || !drives);
  if (reused) *reused = same;
  if (same) return kept->get<dim>();
  return fem::continuum_static<dim>(problem, material, options);
}

template std::optional<fem::ContinuumAnswer<2>> static_ladder<2>(const Problem<2>&, const MaterialDesc&,
                                                                 const fem::ContinuumOptions&, KeptLadders*, bool*);
template std::optional<fem::ContinuumAnswer<3>> static_ladder<3>(const Problem<3>&, const MaterialDesc&,
                                                                 const fem::ContinuumOptions&, KeptLadders*, bool*);

Scene with_overrides(const Scene& scene_in, const RunOverrides& ov) {
  Scene scene = scene_in;
  SolverOverrides{ov.solver, {}, ov.dt, {}}.apply(scene.solver.kind, scene.solver.step.filter, scene.solver.dt,
                                                  scene.solver.springs);
  if (ov.dt) scene.solver.dt_given = true;
  if (ov.duration) {
    if (!(*ov.duration > 0) || !std::isfinite(*ov.duration)) throw InputError("--duration must be a positive number");
    scene.duration = *ov.duration;
    scene.output_interval = std::min(scene.output_interval, scene.duration);
  }
  if (ov.kinematics) {
    const std::optional<Kinematics> named = kinematics_named(*ov.kinematics);
    if (!named) throw InputError("--kinematics must be linear, nonlinear or neo-hookean, not " + *ov.kinematics);
    scene.solver.fem.kinematics = *named;
    if (scene.solver.fem.nonlinear()) scene.solver.fem.scheme = "backward-euler"; // the one it steps with
  }
  if (scene.solver.dt > scene.duration)
    throw InputError("dt " + std::to_string(scene.solver.dt) + " exceeds the duration");
  return scene;
}

RunTables run(const Scene& scene, const std::filesystem::path& out_dir, bool frames, const FitProgress& progress) {
  RunTables tables;
  if (scene.solver.kind == solvers::kFem)
    fem::run_scene(scene, out_dir, frames, &tables);
  else if (scene.solver.kind == solvers::kBullet)
    run_bullet_scene(scene, out_dir, frames, &tables);
  else {
    const Yardstick yardstick = continuum_yardstick();
    run_scene(scene, out_dir, frames, progress, &tables, &yardstick);
  }
  return tables;
}

template RunReport run_solver<2>(const Scene&, const Model<2>&, const std::string&, double, Trajectory<2>&);
template RunReport run_solver<3>(const Scene&, const Model<3>&, const std::string&, double, Trajectory<3>&);

} // namespace vtb::harness
