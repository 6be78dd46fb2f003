#include "vtb/harness/compare.hh"
#include "vtb/problem/cell_fields.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/harness/solvers.hh"

#include "vtb/fem/continuum.hh"

#include "vtb/problem/output.hh"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

namespace vtb::harness {
namespace {

/// The scene as `compare` runs the FEM named `name`: `fem` is the continuum (P2 at the
/// coarsest refinement the static ladder found within 1 % of the next, continuum.hh), `fem-mesh`
/// the scene's own FEM. `note` says which.
template <int dim>
Scene fem_scene(const Scene& scene, const Model<dim>& model, const std::string& name, std::string& note,
                KeptLadders* kept) {
  Scene s = scene;
  if (name != solvers::kFem) {
    note = "the scene's FEM: P" + std::to_string(s.solver.fem.degree) + ", " +
           std::to_string(s.solver.fem.refinements) + " refinements, on the mesh" +
           (s.solver.fem.nonlinear() ? std::string(", ") + kinematics_name(s.solver.fem.kinematics) : "");
    return s;
  }
  s.solver.fem.degree = 2;
  const auto ladder = static_ladder<dim>(model, scene.material, {}, kept); // the load check's
  s.solver.fem.refinements = ladder ? ladder->sufficient_refinements : 0;
  note = ladder ? "the continuum: P2 refined " + std::to_string(s.solver.fem.refinements) +
                      "x (static ladder: " + ladder->how + ")"
                : "P2 on the mesh (the static ladder's first level is above its budget of dofs)";
  if (s.solver.fem.nonlinear()) note += std::string(", ") + kinematics_name(s.solver.fem.kinematics);
  return s;
}

template <int dim>
CompareResult compare_impl(const Scene& scene, const Model<dim>& model, const std::vector<std::string>& solvers,
                           const std::string& reference, double dt, std::ostream* progress, const KeepRuns& keep,
                           KeptLadders* kept) {
  CompareResult res;
  res.scene = scene.name;
  res.reference = reference;
  res.geometrically_exact_fem = scene.solver.fem.nonlinear();
  res.nodes = model.num_nodes();
  res.duration = model.duration;
  std::vector<std::string> all = solvers;
  if (std::find(all.begin(), all.end(), reference) == all.end()) all.push_back(reference);
  std::map<std::string, Trajectory<dim>> runs;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const std::string& name = all[k];
    if (progress) *progress << "[" << k + 1 << "/" << all.size() << "] " << name << " ..." << std::flush;
    const auto a = std::chrono::steady_clock::now();
    CompareRow row;
    row.solver = name;
    if (name == solvers::kFem || name == solvers::kFemMesh) {
      const Scene fs = fem_scene(scene, model, name, name == reference ? res.reference_note : row.note, kept);
      row.report = run_solver(fs, model, solvers::kFem, dt, runs[name]);
      row.report.solver = name;
    } else {
      row.report = run_solver(scene, model, name, dt, runs[name]);
    }
    row.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
    if (progress) *progress << " " << std::fixed << std::setprecision(2) << row.wall_seconds << " s\n";
    if (!keep.runs_dir.empty()) {
      write_run_outputs(keep.runs_dir / name, model, runs[name], row.report, scene.name);
      if (keep.frames) write_frames(model, runs[name], keep.runs_dir / name);
    }
    res.rows.push_back(std::move(row));
  }
  for (const auto& l : model.loads)
    if (l.facets.empty() && l.nodes.size() == 1) res.point_loads.push_back(l.name);
  const std::vector<char> away = away_from_loads(model);
  for (auto& row : res.rows) {
    row.error = compare(runs[row.solver], runs[reference], &away);
    if (!row.report.stable) { // the samples before the blow-up say nothing about accuracy
      const double nan = std::numeric_limits<double>::quiet_NaN();
      row.error.displacement_max = row.error.displacement_final = row.error.probe_max = nan;
      row.error.probe_final = row.error.reaction_max = row.error.reaction_final = nan;
    }
  }
  // The decomposition, from whatever of its three runs exist.
  std::string filtered;
  for (const char* f : {solvers::kFiltered, solvers::kFilteredFull, solvers::kFilteredNeighbors})
    if (runs.count(f)) {
      filtered = f;
      break;
    }
  auto add = [&](const std::string& a, const std::string& b, const char* meaning) {
    if (!a.empty() && runs.count(a) && runs.count(b))
      res.decomposition.push_back({a, b, meaning, compare(runs[a], runs[b])});
  };
  add(filtered, solvers::kCvode, "time-integration error of the approximation");
  add(solvers::kCvode, solvers::kFem, "modelling error of springs vs continuum");
  add(filtered, solvers::kFem, "what a user sees");
  return res;
}

std::string num(double x) {
  std::ostringstream os;
  os << std::setprecision(6) << x;
  return os.str();
}

} // namespace

CompareResult run_compare(const Scene& scene, const std::vector<std::string>& solvers, const std::string& reference,
                          double dt, std::ostream* progress, const KeepRuns& keep) {
  if (reference != solvers::kFem && reference != solvers::kFemMesh && reference != solvers::kCvode)
    throw InputError("--reference must be fem, fem-mesh or cvode, not " + reference);
  for (const auto& s : solvers)
    if (s != solvers::kFemMesh) solvers::find(s, "--solvers"); // an unknown name: InputError with the nearest one
  KeptLadders kept;                                            // the load check's static ladder
  const Yardstick yardstick = continuum_yardstick(&kept);      // the default springs, as vtb run builds them
  return with_model(
      scene,
      [&](const auto& model) {
        constexpr int dim = std::decay_t<decltype(model)>::dimension;
        return compare_impl<dim>(scene, model, solvers, reference, dt, progress, keep, &kept);
      },
      {}, &yardstick);
}

void write_compare(const CompareResult& r, const std::filesystem::path& dir) {
  std::ostringstream c, d;
  c << "solver,reference,nodes,dt,steps,stable,displacement_error_max,displacement_error_final,probe_error_max,"
       "reaction_error_max,reaction_error_final,precompute_seconds,step_median_seconds,step_p99_seconds,total_seconds,"
       "real_time_factor,displacement_error_away_max\n";
  for (const auto& row : r.rows) {
    const auto& p = row.report;
    c << row.solver << ',' << r.reference << ',' << r.nodes << ',' << num(p.dt) << ',' << p.steps_taken << ','
      << (p.stable ? "true" : "false") << ',' << num(row.error.displacement_max) << ','
      << num(row.error.displacement_final) << ',' << num(row.error.probe_max) << ',' << num(row.error.reaction_max)
      << ',' << num(row.error.reaction_final) << ',' << num(p.precompute_seconds) << ',' << num(p.step_seconds.median)
      << ',' << num(p.step_seconds.p99) << ',' << num(row.wall_seconds) << ','
      << (p.stable ? num(r.duration / row.wall_seconds) : std::string("")) // no speed for a run that failed
      << ',' << num(row.error.displacement_away_max) << '\n';
  }
  d << "run,against,meaning,displacement_error_max,displacement_error_final,reaction_error_max\n";
  for (const auto& x : r.decomposition)
    d << x.a << ',' << x.b << ",\"" << x.meaning << "\"," << num(x.error.displacement_max) << ','
      << num(x.error.displacement_final) << ',' << num(x.error.reaction_max) << '\n';
  write_files_atomically(dir, {{"compare.csv", c.str()}, {"decomposition.csv", d.str()}});
}

std::string format_compare(const CompareResult& r) {
  std::ostringstream os;
  char line[256];
  os << "scene " << r.scene << ": " << r.nodes << " nodes, " << r.duration << " s simulated, reference " << r.reference
     << (r.reference_note.empty() ? "" : " (" + r.reference_note + ")") << "\n";
  std::snprintf(line, sizeof line, "%-20s %10s %7s %12s %12s %12s %12s %12s %9s\n", "solver", "dt [s]", "stable",
                "disp err", "final err", "react err", "precomp [ms]", "step [us]", "RT factor");
  os << line;
  for (const auto& row : r.rows) {
    const auto& p = row.report;
    // A run that went unstable has no accuracy and no real-time factor worth printing.
    char rt[32] = "-";
    if (p.stable) std::snprintf(rt, sizeof rt, "%9.1f", r.duration / row.wall_seconds);
    std::snprintf(line, sizeof line, "%-20s %10.3g %7s %12.3e %12.3e %12.3e %12.3f %12.2f %9s\n", row.solver.c_str(),
                  p.dt, p.stable ? "yes" : "NO", row.error.displacement_max, row.error.displacement_final,
                  row.error.reaction_max, p.precompute_seconds * 1e3, p.step_seconds.median * 1e6, rt);
    os << line;
    if (!p.stable) os << "  " << row.solver << ": unstable (" << p.failure << " at t = " << p.failure_time << " s)\n";
    if (!row.note.empty()) os << "  " << row.solver << ": " << row.note << "\n";
  }
  if (!r.point_loads.empty() && r.reference != solvers::kCvode) {
    os << "note: point load";
    for (const auto& n : r.point_loads) os << " " << n;
    os << ": under a point force the continuum displacement is singular (log r in 2D, 1/r in 3D), so the FEM "
          "reference does not converge there; see the error away from the loads (compare.csv "
          "displacement_error_away_max), or load a patch ([[load]] disc)\n";
  }
  // The regime, from the reference's run (the linear FEM is the one it concerns; a geometrically
  // exact FEM holds beyond it).
  for (const auto& row : r.rows)
    if (row.solver == r.reference && !(r.geometrically_exact_fem && r.reference != solvers::kCvode))
      if (const std::string note = small_strain_regime_note(row.report.max_rotation, row.report.max_strain);
          !note.empty())
        os << "note: " << note << "\n";
  if (!r.decomposition.empty()) {
    os << "error decomposition (max over time of the relative L2 displacement error):\n";
    for (const auto& x : r.decomposition) {
      std::snprintf(line, sizeof line, "  %-18s vs %-6s %12.3e   %s\n", x.a.c_str(), x.b.c_str(),
                    x.error.displacement_max, x.meaning.c_str());
      os << line;
    }
  }
  return os.str();
}

} // namespace vtb::harness
