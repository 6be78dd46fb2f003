#include "vtb/solvers/simulation.hh"

#include "vtb/problem/solver_registry.hh"
#include "vtb/solvers/filter_pick.hh"

#include "vtb/meshes/vtu_io.hh"
#include "vtb/problem/cell_fields.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/cvode_solver.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"
#include "vtb/springs/calibration.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace vtb {

template <int dim>
void support_reactions(const Model<dim>& model, const State<dim>& s, Nodal<dim>& scratch, Nodal<dim>& ext,
                       std::vector<Vec<dim>>& out) {
  model.external_forces(s.t, ext);
  if (s.applied.cols() == ext.cols()) ext += s.applied;
  scratch = ext;
  add_internal_forces(model.net, s.u, s.v, scratch);
  out.resize(model.supports.size());
  for (std::size_t k = 0; k < model.supports.size(); ++k) {
    Vec<dim> r = Vec<dim>::Zero();
    for (int i : model.supports[k].nodes) r -= scratch.col(i);
    out[k] = r;
  }
}

template <int dim>
void record_sample(const Model<dim>& model, const State<dim>& s, Trajectory<dim>& traj, bool record_field,
                   RunReport& rep) {
  traj.t.push_back(s.t);
  std::vector<Vec<dim>> pu;
  for (std::size_t p = 0; p < model.probes.size(); ++p) pu.push_back(model.probe_displacement(p, s.u));
  traj.probe_u.push_back(std::move(pu));
  Nodal<dim> scratch(dim, model.num_nodes()), ext(dim, model.num_nodes());
  std::vector<Vec<dim>> reactions;
  support_reactions(model, s, scratch, ext, reactions);
  traj.reaction.push_back(std::move(reactions));
  if (record_field) {
    traj.field.push_back(s.u);
    traj.velocity.push_back(s.v);
  }
  rep.max_spring_strain = std::max(rep.max_spring_strain, max_strain(model.net, s.u));
  const double small = max_small_strain(model.mesh, s.u);
  if (!(small <= rep.max_strain)) rep.max_strain = small; // propagates NaN
  const double rotation = max_rotation(model.mesh, s.u);
  if (!(rotation <= rep.max_rotation)) rep.max_rotation = rotation;
  // The cells' volume ratios over the samples (summary.json): the smallest J and the most cells
  // at J <= 0 at once; every spring run reports them, with or without the volume term.
  const VolumeRatios vr = volume_ratios<dim>(model.mesh.cells, model.net.rest, s.u);
  const auto slot = [&](const char* key, double first) -> double& {
    for (auto& [k, value] : rep.extra)
      if (k == key) return value;
    return rep.extra.emplace_back(key, first).second;
  };
  double& min_ratio = slot("min_volume_ratio", vr.min_ratio);
  if (!(vr.min_ratio >= min_ratio)) min_ratio = vr.min_ratio; // propagates NaN
  double& inverted = slot("inverted_cells", vr.inverted);
  inverted = std::max(inverted, static_cast<double>(vr.inverted));
}

namespace {
/// For the explicit scheme, what its failure means: the step against its stability limit.
std::string explicit_hint(const IntegratorOptions& o, const RunReport& rep) {
  if (o.kind != solvers::kExplicit || !(rep.courant_dt > 0)) return "";
  std::ostringstream os;
  os << "; dt = " << o.dt << " s is " << o.dt / rep.courant_dt << " times the explicit scheme's stability limit "
     << rep.courant_dt << " s (courant_dt_estimate)";
  return os.str();
}
} // namespace

/// What a spring run reports before it starts: sizes, the step, the calibration, the filter's
/// options, and the explicit scheme's predicted limit.
template <int dim> RunReport report_header(const Model<dim>& model, const IntegratorOptions& o) {
  RunReport rep = spring_report(model, o.kind);
  rep.dt = o.dt;
  rep.step_budget = o.step_budget;
  if (o.kind == solvers::kFiltered) {
    rep.filter = chosen_filter(model, o.filter);
    rep.filter_requested = o.filter_requested.empty() ? o.filter : o.filter_requested;
    rep.filter_reason = o.filter_reason;
    rep.momentum_correction = o.momentum_correction && !model.has_constraints();
    rep.strain_limit = o.strain_limit;
  }
  const double w2 = max_omega_squared(model, false);
  const double tau = model.net.stiffness.size() ? model.net.damping[0] / model.net.stiffness[0] : 0.0;
  rep.courant_dt = explicit_critical_dt(w2, tau, model.net.mass_damping);
  return rep;
}

/// Stops the run as unstable at t: why, with the explicit scheme's stability limit when it applies.
void fail(RunReport& rep, const std::string& why, const IntegratorOptions& o, double t) {
  rep.stable = false;
  rep.failure = why + explicit_hint(o, rep);
  rep.failure_time = t;
}

template <int dim>
RunReport simulate(const Model<dim>& model, const IntegratorOptions& o, Trajectory<dim>& traj, bool record_field) {
  if (o.kind == solvers::kCvode)
    return simulate_cvode(model, CvodeOptions{static_cast<const CvodeSettings&>(o)}, traj, record_field);
  const IntegratorOptions picked = with_budget_pick(model, o); // auto within a step budget
  return simulate_with<dim>(
      model, picked, [&] { return make_integrator(model, picked); }, traj, record_field);
}

template <int dim>
RunReport simulate_with(const Model<dim>& model, const IntegratorOptions& o, const IntegratorFactory<dim>& make,
                        Trajectory<dim>& traj, bool record_field) {
  using clock = std::chrono::steady_clock;
  RunReport rep = report_header(model, o);

  const auto t0 = clock::now();
  auto integrator = make();
  rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();

  State<dim> s = initial_state(model);
  // Enough steps to reach the duration; each sample time is interpolated within its step.
  const long steps = std::max(1L, static_cast<long>(std::ceil(model.duration / o.dt - 1e-9)));
  rep.steps = steps;
  SampleSchedule samples(model.duration, model.output_interval);
  traj.t.reserve(samples.size() + 1);
  traj.probe_u.reserve(samples.size() + 1);
  traj.reaction.reserve(samples.size() + 1);
  if (record_field) traj.field.reserve(samples.size() + 1);
  std::vector<double> step_time;
  step_time.reserve(static_cast<std::size_t>(steps));

  const auto loop_start = clock::now();
  auto record = [&]() { record_sample(model, s, traj, record_field, rep); };
  record();
  for (long k = 0; k < steps; ++k) {
    const double t1 = static_cast<double>(k + 1) * o.dt; // no drift from summing dt
    const bool crossing = samples.due(t1, o.dt);
    if (crossing) record(); // the state at the step's start, to interpolate from
    const auto a = clock::now();
    integrator->step(s);
    step_time.push_back(std::chrono::duration<double>(clock::now() - a).count());
    s.t = t1;
    ++rep.steps_taken;
    if (!s.u.allFinite() || !s.v.allFinite()) {
      fail(rep, "non-finite displacement or velocity", o, s.t);
      break;
    }
    if (crossing) {
      record();
      interpolate_last_step(traj, samples.take(t1, o.dt));
      if (!(rep.max_spring_strain <= kRunawayStrain)) {
        fail(rep,
             "runaway strain (a spring beyond " + std::to_string(static_cast<int>(kRunawayStrain * 100)) +
                 "% of its rest length)",
             o, s.t);
        break;
      }
    }
  }
  if (o.step_budget > 0)
    rep.steps_over_budget =
        std::count_if(step_time.begin(), step_time.end(), [&](double t) { return t > o.step_budget; });
  rep.step_seconds = step_stats(std::move(step_time));
  // The tensor filters' steps taken by implicit Euler (their warped Jacobian past trust).
  if (const auto* f = dynamic_cast<const FilteredImplicit<dim>*>(integrator.get()); f && f->has_fallback()) {
    rep.extra.emplace_back("tensor_fallback_steps", static_cast<double>(f->fallback_steps()));
    rep.fallback_steps = f->fallback_steps();
    rep.extra.emplace_back("tensor_relinearizations", static_cast<double>(f->relinearizations()));
    rep.extra.emplace_back("tensor_refactorizations", static_cast<double>(f->refactorizations()));
    rep.extra.emplace_back("tensor_refreshes_at_once", static_cast<double>(f->refreshes_at_once()));
    rep.extra.emplace_back("tensor_extra_corrections", static_cast<double>(f->extra_corrections()));
  }
  if (!rep.filter.empty())
    rep.filter_most_steps =
        2 * rep.fallback_steps > rep.steps_taken ? std::string(solvers::kImplicitEuler) : rep.filter;
  rep.total_seconds = std::chrono::duration<double>(clock::now() - loop_start).count();
  return rep;
}

IntegratorOptions integrator_options(const SolverDesc& s) {
  IntegratorOptions o;
  static_cast<SpringStepSettings&>(o) = s.step;
  static_cast<CvodeSettings&>(o) = s.cvode;
  o.kind = s.kind;
  o.dt = s.dt;
  return o;
}

RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames, const FitProgress& progress,
                    RunTables* tables, const Yardstick* yardstick) {
  const IntegratorOptions o = integrator_options(scene.solver);
  return with_model(
      scene,
      [&](const auto& model) {
        constexpr int dim = std::decay_t<decltype(model)>::dimension;
        Trajectory<dim> traj;
        RunReport rep = simulate(model, o, traj, frames && !out_dir.empty());
        finish_run(out_dir, model, traj, rep, scene.name, tables);
        if (frames && !out_dir.empty()) write_frames(model, traj, out_dir);
        return rep;
      },
      progress, yardstick);
}

template <int dim>
void write_frames(const Model<dim>& model, const Trajectory<dim>& traj, const std::filesystem::path& dir) {
  ensure_directory(dir / "frames");
  std::vector<float> strain;
  std::vector<double> force;
  for (std::size_t k = 0; k < traj.field.size(); ++k) {
    cell_max_principal_strain(model.mesh, traj.field[k], strain);
    cell_spring_force(model.mesh, model.net, traj.field[k], force);
    std::vector<VtuField> fields = {point_vectors<dim>("displacement", traj.field[k])};
    if (k < traj.velocity.size()) fields.push_back(point_vectors<dim>("velocity", traj.velocity[k]));
    fields.push_back(VtuField{"max_principal_strain", 1, true, std::vector<double>(strain.begin(), strain.end())});
    fields.push_back(VtuField{"spring_force", 1, true, force});
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.vtu", k);
    write_vtu(model.mesh, dir / "frames" / name, fields);
  }
  write_pvd(dir, traj.t);
}

template void write_frames<2>(const Model<2>&, const Trajectory<2>&, const std::filesystem::path&);
template void write_frames<3>(const Model<3>&, const Trajectory<3>&, const std::filesystem::path&);
template RunReport simulate<2>(const Model<2>&, const IntegratorOptions&, Trajectory<2>&, bool);
template RunReport simulate_with<2>(const Model<2>&, const IntegratorOptions&, const IntegratorFactory<2>&,
                                    Trajectory<2>&, bool);
template RunReport simulate_with<3>(const Model<3>&, const IntegratorOptions&, const IntegratorFactory<3>&,
                                    Trajectory<3>&, bool);
template RunReport simulate<3>(const Model<3>&, const IntegratorOptions&, Trajectory<3>&, bool);
template void record_sample<2>(const Model<2>&, const State<2>&, Trajectory<2>&, bool, RunReport&);
template void record_sample<3>(const Model<3>&, const State<3>&, Trajectory<3>&, bool, RunReport&);
template void support_reactions<2>(const Model<2>&, const State<2>&, Nodal<2>&, Nodal<2>&, std::vector<Vec<2>>&);
template void support_reactions<3>(const Model<3>&, const State<3>&, Nodal<3>&, Nodal<3>&, std::vector<Vec<3>>&);

namespace solvers {
IntegratorOptions integrator_options(const Entry& entry, const SolverDesc& solver) {
  IntegratorOptions o = vtb::integrator_options(solver);
  o.kind = entry.kind;
  if (*entry.filter) o.filter = entry.filter;
  return o;
}
} // namespace solvers

} // namespace vtb
