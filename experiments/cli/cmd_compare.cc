#include "commands.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/harness/compare.hh"
#include "vtb/harness/solvers.hh"

#include <iostream>
#include <memory>
#include <optional>

namespace vtb::cli {

Action add_compare(CLI::App& app) {
  struct Opts {
    std::string scene, reference = solvers::kFem, out, kinematics;
    std::vector<std::string> solvers;
    std::optional<double> dt; ///< absent: the scene's
    bool frames = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("compare", "Run several solvers on a scene; errors against a reference, timing, "
                                                "and the error decomposition (compare.csv, decomposition.csv)");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--solvers", o->solvers, "Comma-separated: " + solvers::list())->delimiter(',')->required();
  cmd->add_option("--reference", o->reference,
                  "fem (default: the continuum, P2 refined until converged), fem-mesh (the scene's own FEM, P1 on the "
                  "mesh by default) or cvode");
  add_kinematics_option(cmd, o->kinematics);
  cmd->add_option("--dt", o->dt, "Step for every fixed-step solver (default: the scene's)");
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene>-compare)");
  cmd->add_flag("--frames", o->frames, "Also write each solver's frames.pvd and frames/*.vtu in OUT/<solver>/");
  return [o]() {
    harness::RunOverrides ov;
    if (!o->kinematics.empty()) ov.kinematics = o->kinematics;
    const Scene scene = harness::with_overrides(read_scene(o->scene), ov);
    const double dt = o->dt ? checked_dt(*o->dt) : 0.0; // 0: the scene's (run_compare)
    const std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / (scene.name + "-compare") : std::filesystem::path(o->out);
    // Each solver's own run outputs (probes.csv, reactions.csv, summary.json) in OUT/<solver>/.
    const auto res = harness::run_compare(scene, o->solvers, o->reference, dt, &std::cerr, {out, o->frames});
    harness::write_compare(res, out);
    std::cout << harness::format_compare(res) << "outputs in " << out.string() << "\n";
    return 0;
  };
}

} // namespace vtb::cli
