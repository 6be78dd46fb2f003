#include "commands.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/harness/study.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_study(CLI::App& app) {
  struct Opts {
    std::string scene, reference = solvers::kFem, out;
    std::vector<std::string> solvers;
    bool quick = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "study", "Accuracy against cost on a scene: dt ladders, cvode's rtol ladder, errors against a converged "
               "reference, the Pareto front (study.csv, study_plot.tex and .png)");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--solvers", o->solvers,
                  "Comma-separated, of " + solvers::list(solvers::is_spring) + " (default all but filtered)")
      ->delimiter(',');
  cmd->add_option("--reference", o->reference, "fem (P2, one refinement, dt/4; default) or cvode (rtol 1e-10)");
  cmd->add_flag("--quick", o->quick, "Short ladders and at most 1 s of simulated time");
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene>-study)");
  return [o]() {
    const Scene scene = read_scene(o->scene);
    harness::StudyOptions so;
    if (!o->solvers.empty()) so.solvers = o->solvers;
    so.reference = o->reference;
    so.quick = o->quick;
    const auto res = harness::run_study(scene, so, &std::cerr);
    const std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / (scene.name + "-study") : std::filesystem::path(o->out);
    std::string note;
    const auto png = harness::write_study(res, out, note);
    std::cout << harness::format_study(res) << "outputs in " << out.string() << "\n";
    if (png.empty()) std::cout << "vtb study: " << note << "\n";
    return 0;
  };
}

} // namespace vtb::cli
