#include "commands.hh"
#include "vtb/harness/ranks.hh"
#include "vtb/problem/solver_names.hh"

#include "vtb/harness/sweep.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_sweep(CLI::App& app) {
  struct Opts {
    std::string scene, out;
    std::vector<double> dts, scales{1.0};
    std::vector<std::string> solvers = harness::default_sweep_solvers();
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("sweep", "Stability map over time step and stiffness scale (stability.csv)");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--dt", o->dts, "Comma-separated time steps (s)")->delimiter(',')->required();
  cmd->add_option("--stiffness-scale", o->scales, "Comma-separated factors on Young's modulus")->delimiter(',');
  cmd->add_option("--solvers", o->solvers, "Comma-separated solvers")->delimiter(',');
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene>-sweep)");
  return [o]() {
    const Scene scene = read_scene(o->scene);
    const auto cells = harness::run_sweep(scene, o->dts, o->scales, o->solvers, &std::cerr);
    if (!harness::world().root()) return 0; // under mpirun rank 0 gathered every cell; it alone writes
    const std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / (scene.name + "-sweep") : std::filesystem::path(o->out);
    harness::write_sweep(cells, out / "stability.csv");
    std::cout << "criterion: " << harness::kStabilityCriterion << "\n";
    for (const auto& c : cells)
      std::cout << c.solver << " dt=" << c.dt << " (" << c.dt / c.courant_dt
                << " x explicit limit) scale=" << c.stiffness_scale << ": " << (c.stable ? "stable" : "UNSTABLE")
                << ", error " << c.error << "\n";
    std::cout << "outputs in " << out.string() << "\n";
    return 0;
  };
}

} // namespace vtb::cli
