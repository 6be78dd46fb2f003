#include "vtb/harness/sweep.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/base/atomic_file.hh"

#include "vtb/harness/solvers.hh"
#include "vtb/solvers/explicit_euler.hh"

#include "vtb/harness/ranks.hh"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <optional>
#include <ostream>
#include <sstream>

namespace vtb::harness {
namespace {

/// One cell of the map, in the serial order: scale, then solver, then dt.
struct Task {
  std::size_t scale = 0;
  std::string solver;
  double dt = 0; ///< as asked (the run takes the nearest that divides the output interval)
};

/// A cell as exact text for the gather on rank 0 (hexadecimal doubles keep every bit, NaN too).
std::string encode(long index, const SweepCell& c) {
  char line[512];
  std::snprintf(line, sizeof line, "%ld %a %a %a %a %d %a %a %a ", index, c.dt, c.stiffness_scale, c.young_modulus,
                c.courant_dt, c.stable ? 1 : 0, c.max_strain, c.step_median, c.error);
  return line + c.solver + '\t' + c.failure + '\n';
}

std::pair<long, SweepCell> decode(const std::string& line) {
  std::istringstream in(line);
  std::string f[9];
  for (auto& x : f) in >> x;
  const auto d = [&](int k) { return std::strtod(f[k].c_str(), nullptr); };
  SweepCell c;
  c.dt = d(1), c.stiffness_scale = d(2), c.young_modulus = d(3), c.courant_dt = d(4);
  c.stable = f[5] == "1";
  c.max_strain = d(6), c.step_median = d(7), c.error = d(8);
  in.get();
  std::getline(in, c.solver, '\t');
  std::getline(in, c.failure);
  return {std::stol(f[0]), c};
}

template <int dim>
std::vector<SweepCell> sweep_impl(const Scene& scene_in, const Mesh<dim>& mesh, const std::vector<double>& dts,
                                  const std::vector<double>& scales, const std::vector<std::string>& solvers,
                                  std::ostream* progress, bool across_ranks) {
  std::vector<Task> tasks;
  for (std::size_t s = 0; s < scales.size(); ++s)
    for (const auto& solver : solvers)
      for (double dt : dts) tasks.push_back({s, solver, dt});
  // The scale in hand: its model, the explicit limit and the CVODE reference (each rank makes
  // those of the scales whose cells it takes; the cells come grouped by scale).
  std::size_t current = scales.size();
  const Yardstick yardstick = continuum_yardstick(); // the default springs' fit target, as vtb run's
  std::optional<Model<dim>> model;
  Scene scene = scene_in;
  Trajectory<dim> ref;
  RunReport rr;
  double courant = 0;
  std::string mine;
  CellQueue queue(static_cast<long>(tasks.size()), across_ranks);
  for (long k; (k = queue.next()) >= 0;) {
    const Task& t = tasks[static_cast<std::size_t>(k)];
    if (t.scale != current) {
      current = t.scale;
      scene = scene_in;
      scene.material.young_modulus *= scales[current];
      model.emplace(build_model<dim>(scene, Mesh<dim>(mesh), {}, false, &yardstick));
      model->output_interval = model->duration / 20;
      const double w2 = max_omega_squared(*model, model->free_nodes.size() * dim <= 1500);
      courant = explicit_critical_dt(w2, scene.material.retardation_time, scene.material.mass_damping);
      ref = Trajectory<dim>{};
      rr = run_solver(scene, *model, solvers::kCvode, 0, ref);
    }
    SweepCell c;
    c.solver = t.solver;
    c.stiffness_scale = scales[current];
    c.young_modulus = scene.material.young_modulus;
    c.courant_dt = courant;
    c.dt = model->output_interval / std::ceil(model->output_interval / t.dt - 1e-9);
    Trajectory<dim> tr;
    const RunReport r = run_solver(scene, *model, t.solver, c.dt, tr);
    c.stable = r.stable;
    c.failure = r.failure;
    c.max_strain = r.max_strain;
    c.step_median = r.step_seconds.median;
    c.error = rr.stable && r.stable ? compare(tr, ref).displacement_max : std::nan("");
    mine += encode(k, c);
    if (progress)
      *progress << "  scale " << c.stiffness_scale << " " << c.solver << " dt " << std::setprecision(3) << c.dt << ": "
                << (c.stable ? "stable" : "UNSTABLE") << "\n";
  }
  // Every rank's cells to rank 0, in the serial order there.
  std::vector<std::pair<long, SweepCell>> all;
  for (const std::string& part : across_ranks ? gather_on_root(mine) : std::vector<std::string>{mine}) {
    std::istringstream in(part);
    for (std::string line; std::getline(in, line);) all.push_back(decode(line));
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<SweepCell> cells;
  for (auto& [k, c] : all) cells.push_back(std::move(c));
  return cells;
}

} // namespace

std::vector<SweepCell> run_sweep(const Scene& scene_in, const std::vector<double>& dts,
                                 const std::vector<double>& scales, const std::vector<std::string>& solvers,
                                 std::ostream* progress, bool across_ranks) {
  if (dts.empty() || scales.empty()) throw InputError("vtb sweep: --dt and --stiffness-scale need at least one value");
  for (double dt : dts) checked_dt(dt);
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
  if (across_ranks && !world().root()) progress = nullptr; // rank 0 alone prints
  return with_mesh(scene_in, [&](auto& mesh) {
    constexpr int dim = std::decay_t<decltype(mesh)>::points_dim;
    return sweep_impl<dim>(scene_in, mesh, dts, scales, solvers, progress, across_ranks);
  });
}

std::vector<std::string> default_sweep_solvers() {
  return {solvers::kExplicit, solvers::kFilteredNeighbors, solvers::kFilteredFull, solvers::kImplicitEuler};
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
