#include "commands.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/harness/solvers.hh"
#include "vtb/harness/study.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_study(CLI::App& app) {
  struct Opts {
    std::string scene, reference = solvers::kFem, out, kinematics;
    std::vector<std::string> solvers;
    std::string shard;
    bool quick = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "study", "Accuracy against cost on a scene: dt ladders, cvode's rtol ladder, errors against a converged "
               "reference, the Pareto front (study.csv, study_plot.tex and .png)");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--solvers", o->solvers,
                  "Comma-separated, of " + solvers::list(solvers::is_spring) +
                      " (default: every filter that suits the scene, implicit-euler, explicit, cvode)")
      ->delimiter(',');
  cmd->add_option("--reference", o->reference,
                  "fem (the continuum: P2 at the static ladder's level, at dt or the smaller step its measured time "
                  "error needs; default) or cvode (rtol 1e-10)");
  add_kinematics_option(cmd, o->kinematics);
  cmd->add_flag("--quick", o->quick, "Short ladders and at most 1 s of simulated time");
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene>-study)");
  cmd->add_option("--shard", o->shard,
                  "K/N: run only the K-th of N parts (0 <= K < N) of the study, for a job array; vtb merge joins them");
  return [o]() {
    harness::RunOverrides ov;
    if (!o->kinematics.empty()) ov.kinematics = o->kinematics;
    const Scene scene = harness::with_overrides(read_scene(o->scene), ov);
    harness::StudyOptions so;
    if (!o->solvers.empty()) so.solvers = o->solvers;
    so.reference = o->reference;
    so.quick = o->quick;
    if (!o->shard.empty()) so.shard = harness::parse_shard(o->shard);
    const auto res = harness::run_study(scene, so, &std::cerr);
    if (!harness::world().root() && !so.shard.active()) return 0; // rank 0 prints and writes
    std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / (scene.name + "-study") : std::filesystem::path(o->out);
    if (so.shard.active() && o->out.empty())
      out += "-part" + std::to_string(so.shard.index) + "of" + std::to_string(so.shard.count);
    return finish_study(res, out);
  };
}

int finish_study(const harness::StudyResult& res, const std::filesystem::path& out) {
  std::string note;
  const auto png = harness::write_study(res, out, note);
  std::cout << harness::format_study(res) << "outputs in " << out.string() << "\n";
  if (png.empty()) std::cout << "vtb study: " << note << "\n";
  if (res.timing_shared)
    std::cerr << "vtb study: warning: two ranks of one node may share a core (study.csv's binding column): their "
                 "step times may be each other's; bind ranks to cores (mpirun --bind-to core) with at most one per "
                 "core\n";
  return 0;
}

Action add_merge(CLI::App& app) {
  struct Opts {
    std::vector<std::string> parts;
    std::string out;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "Join the parts of a sharded study (vtb study --shard K/N) into one study.csv, study.json and plot");
  cmd->add_option("parts", o->parts, "The parts' output folders")->required();
  cmd->add_option("--out", o->out, "Output folder")->required();
  return [o]() {
    std::vector<std::filesystem::path> dirs(o->parts.begin(), o->parts.end());
    return finish_study(harness::merge_studies(dirs), o->out);
  };
}

} // namespace vtb::cli
