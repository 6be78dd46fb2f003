#include "commands.hh"
#include "fit_progress.hh"
#include "overrides.hh"
#include "vtb/problem/cell_fields.hh"
#include "vtb/problem/solver_registry.hh"
#include "vtb/problem/support_notes.hh"

#include "vtb/harness/ranks.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/springs/load_check.hh"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <unistd.h>

namespace vtb::cli {

Action add_run(CLI::App& app) {
  struct Opts {
    std::string scene, solver, out, kinematics;
    std::optional<double> dt, duration; ///< absent: the scene's
    bool frames = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd =
      app.add_subcommand("run", "Run one simulation of a scene and write probes.csv, reactions.csv, summary.json");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--solver", o->solver,
                  "Override [solver].kind (and filter): " + solvers::list() + " (vtb solvers describes each)");
  cmd->add_option("--dt", o->dt, "Override [solver].dt (s)");
  cmd->add_option("--duration", o->duration, "Override [scene].duration (s)");
  add_kinematics_option(cmd, o->kinematics);
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene name>)");
  cmd->add_flag("--frames", o->frames, "Also write frames.pvd and frames/*.vtu (one per sample) for ParaView");
  return [o]() {
    const Scene scene = read_scene(o->scene);
    RunOverrides ov;
    if (!o->solver.empty()) ov.solver = o->solver;
    ov.dt = o->dt;
    ov.duration = o->duration;
    if (!o->kinematics.empty()) ov.kinematics = o->kinematics;
    const std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / scene.name : std::filesystem::path(o->out);
    const Scene run = with_overrides(scene, ov);
    // Under mpirun the FEM spreads its mesh over the ranks; a spring solver runs on rank 0 alone.
    if (run.solver.kind != solvers::kFem && !harness::world().root()) return 0;
    for (const auto& note : support_face_notes(run)) std::cout << "vtb run: note: " << note << "\n";
    const RunReport r = harness::run(run, out, o->frames, fit_progress_line(std::cerr, isatty(2) != 0)).report;
    std::string filter; // what a filtered run ran, and whether auto picked it
    if (!r.filter.empty())
      filter = " (" + r.filter +
               (r.filter_requested != r.filter ? " filter, picked by " + r.filter_requested : " filter") +
               (r.filter_reason.empty() ? "" : ": " + r.filter_reason) + ")";
    std::string springs; // which constants, and what auto or the fit's guard chose
    if (!r.calibration.empty())
      springs =
          " " + r.calibration + (r.calibration_requested != r.calibration ? " (" + r.calibration_requested + ")" : "");
    std::string volume_cells; // the volume term's cells beside the springs (docs/volume_term.md)
    for (const auto& [key, value] : r.extra)
      if (key == "volume_cells")
        volume_cells = " and " + std::to_string(static_cast<long>(value)) + " cells' volume term";
    if (!r.calibration_note.empty()) std::cout << "vtb run: " << r.calibration_note << "\n";
    if (!r.calibration_target.empty() && r.calibration_target.rfind("the continuum", 0) != 0)
      std::cout << "vtb run: the fit trained on " << r.calibration_target << "\n";
    if (r.fallback_steps > 0) // the filter's claim does not hold on these steps: say so
      std::cout << "vtb run: " << r.fallback_steps << " of " << r.steps_taken << " steps (" << std::setprecision(3)
                << 100.0 * static_cast<double>(r.fallback_steps) / static_cast<double>(r.steps_taken)
                << std::setprecision(6) << " %) fell back to implicit Euler (the " << r.filter
                << " filter's safety net, for a state whose distortion is not finite, docs/method.md); most steps: "
                << r.filter_most_steps << "\n";
    if (r.step_budget > 0) // the budget's promise, kept or not
      std::cout << "vtb run: " << r.steps_over_budget << " of " << r.steps_taken << " steps (" << std::setprecision(3)
                << (r.steps_taken > 0
                        ? 100.0 * static_cast<double>(r.steps_over_budget) / static_cast<double>(r.steps_taken)
                        : 0.0)
                << std::setprecision(6) << " %) took longer than the step budget of " << r.step_budget * 1e6 << " us\n";
    std::string load_check; // the springs against the yardstick (the continuum) on this scene's loads
    if (std::isfinite(r.calibration_load_error)) {
      const auto pct = [](double x) {
        std::ostringstream s;
        s << std::setprecision(2) << 100 * x << " %";
        return s.str();
      };
      const bool continuum = std::isfinite(r.mesh_fem_load_error);
      load_check = " (" + pct(r.calibration_load_error) + " from " + (continuum ? "the continuum" : "P1 FEM") +
                   " on the scene's loads, static" + (r.calibration_own_loads ? ", which it was trained on" : "") +
                   (continuum ? "; P1 on this mesh " + pct(r.mesh_fem_load_error) : std::string()) + ")";
      std::cout << "vtb run: the springs' load check against " << r.calibration_yardstick << "\n";
      if (r.calibration_load_error > kLoadErrorGoal)
        std::cout << "vtb run: the " << r.calibration << " springs are " << pct(r.calibration_load_error) << " from "
                  << (continuum ? "the continuum" : "P1 FEM") << " on this scene's loads (static, linear; above "
                  << 100 * kLoadErrorGoal << " %): "
                  << (r.calibration.rfind("fitted", 0) == 0
                          ? "central springs miss part of this response (bending of a part a few cells thick, a "
                            "load concentrated at an edge or corner, or nu near 0.5; docs/fidelity.md)"
                          : "springs = \"fitted\" fits them to the FEM (docs/fidelity.md)")
                  << "; vtb compare --reference fem measures the run\n";
    }
    std::cout << "vtb run: " << scene.name << " with " << r.solver << filter << ", " << r.nodes << " nodes, "
              << r.springs << springs << " springs" << volume_cells << load_check << ", dt = " << r.dt << " s, "
              << r.steps_taken << " steps; precompute " << r.precompute_seconds * 1e3 << " ms, step median "
              << r.step_seconds.median * 1e6 << " us, p99 " << r.step_seconds.p99 * 1e6 << " us; max strain "
              << r.max_strain << "; outputs in " << out.string() << "\n";
    if (run.solver.kind != solvers::kFem || !run.solver.fem.nonlinear())
      if (const std::string note = large_strain_run_note(r.max_rotation, r.max_strain, !load_check.empty());
          !note.empty())
        std::cout << "vtb run: " << note << "\n";
    if (!r.stable) {
      std::cerr << "vtb: unstable: " << r.failure << " at t = " << r.failure_time << " s (" << r.solver
                << ", dt = " << r.dt << " s); summary.json records stable = false\n";
      return 2;
    }
    return 0;
  };
}

} // namespace vtb::cli
