#include "vtb/harness/sweep.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/meshes/atomic_file.hh"

#include "vtb/harness/solvers.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>

namespace vtb::harness {
namespace {

template <int dim>
void sweep_scale(const Scene& scene, Model<dim> model, double scale, const std::vector<double>& dts,
                 const std::vector<std::string>& solvers, std::vector<SweepCell>& out, std::ostream* progress) {
  model.output_interval = model.duration / 20;
  const double tau = scene.material.retardation_time;
  const double w2 = max_omega_squared(model, model.free_nodes.size() * dim <= 1500);
  const double courant = explicit_critical_dt(w2, tau, scene.material.mass_damping);
  Trajectory<dim> ref;
  const RunReport rr = run_solver(scene, model, solvers::kCvode, 0, ref);
  for (const auto& solver : solvers)
    for (double dt_req : dts) {
      SweepCell c;
      c.solver = solver;
      c.stiffness_scale = scale;
      c.young_modulus = scene.material.young_modulus;
      c.courant_dt = courant;
      c.dt = model.output_interval / std::ceil(model.output_interval / dt_req - 1e-9);
      Trajectory<dim> tr;
      const RunReport r = run_solver(scene, model, solver, c.dt, tr);
      c.stable = r.stable;
      c.failure = r.failure;
      c.max_strain = r.max_strain;
      c.step_median = r.step_seconds.median;
      c.error = rr.stable && r.stable ? compare(tr, ref).displacement_max : std::nan("");
      out.push_back(c);
      if (progress)
        *progress << "  scale " << scale << " " << solver << " dt " << std::setprecision(3) << c.dt << ": "
                  << (c.stable ? "stable" : "UNSTABLE") << "\n";
    }
}

} // namespace

std::vector<SweepCell> run_sweep(const Scene& scene_in, const std::vector<double>& dts,
                                 const std::vector<double>& scales, const std::vector<std::string>& solvers,
                                 std::ostream* progress) {
  if (dts.empty() || scales.empty()) throw InputError("vtb sweep: --dt and --stiffness-scale need at least one value");
  for (double dt : dts)
    if (!(dt > 0) || !std::isfinite(dt)) throw InputError("vtb sweep: --dt values must be > 0");
  for (double s : scales)
    if (!(s > 0) || !std::isfinite(s)) throw InputError("vtb sweep: --stiffness-scale values must be > 0");
  for (const auto& s : solvers) {
    solvers::find(s, "vtb sweep"); // an unknown name: InputError with the nearest one
    // CVODE chooses its own steps: a dt ladder would run the same integration at every dt
    // and report error 0 against itself.
    if (s == solvers::kCvode || s == solvers::kFem)
      throw InputError("vtb sweep: \"" + s +
                       "\" has no fixed dt to sweep (it is the reference the sweep measures against)");
  }
  std::vector<SweepCell> cells;
  for (double scale : scales) {
    Scene scene = scene_in;
    scene.material.young_modulus *= scale;
    with_model(scene, [&](auto& model) {
      constexpr int dim = std::decay_t<decltype(model)>::dimension;
      sweep_scale<dim>(scene, std::move(model), scale, dts, solvers, cells, progress);
    });
  }
  return cells;
}

void write_sweep(const std::vector<SweepCell>& cells, const std::filesystem::path& file) {
  write_file_atomically(file, [&](std::ostream& f) {
    f << std::setprecision(6);
    f << "solver,dt,stiffness_scale,young_modulus,stable,criterion,failure,max_strain,displacement_error_max,"
         "step_median_seconds,courant_dt,dt_over_courant\n";
    for (const auto& c : cells)
      f << c.solver << ',' << c.dt << ',' << c.stiffness_scale << ',' << c.young_modulus << ','
        << (c.stable ? "true" : "false") << ",\"" << kStabilityCriterion << "\",\"" << c.failure << "\","
        << c.max_strain << ',' << c.error << ',' << c.step_median << ',' << c.courant_dt << ',' << c.dt / c.courant_dt
        << '\n';
  });
}

} // namespace vtb::harness
