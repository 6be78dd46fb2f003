// One way to override a scene's [solver] from outside it (vtb/problem/overrides.hh): `vtb run`'s
// flags (harness::with_overrides), `vtb view`'s flags (initial_controls) and a stepper's live
// controls (LiveSim::configure) give the same solver, filter and step for the same overrides,
// and refuse a bad step with the same line. Python's keyword arguments take the same function
// (tests/python/test_cli_parity.py holds them against the CLI).
#include "../../experiments/viewer/app.hh"
#include "vtb/base/input_error.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/scene.hh"
#include "vtb/stepper/live_sim.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace vtb {
namespace {

Scene plate() {
  return read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/plate123_step.toml");
}

/// The InputError's line a call throws ("" when it throws none).
template <class F> std::string refusal(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Overrides, TheCliAndTheViewerApplyAnOverrideAlike) {
  const Scene scene = plate();
  struct Case {
    std::optional<std::string> solver;
    std::optional<double> dt;
  };
  for (const Case& k : {Case{"filtered-tensor", 2e-3}, Case{"implicit-euler", {}}, Case{{}, 5e-4},
                        Case{"filtered-multigrid", 1e-3}, Case{"explicit", 1e-5}}) {
    harness::RunOverrides run;
    run.solver = k.solver;
    run.dt = k.dt;
    const Scene cli = harness::with_overrides(scene, run);
    viewer::ViewOptions view;
    view.solver = k.solver;
    view.dt = k.dt;
    const SimControls c = viewer::initial_controls(scene, view);
    EXPECT_EQ(c.solver, cli.solver.kind) << k.solver.value_or("(none)");
    EXPECT_EQ(c.filter, cli.solver.step.filter) << k.solver.value_or("(none)");
    EXPECT_EQ(c.dt, cli.solver.dt) << k.solver.value_or("(none)");
  }
}

TEST(Overrides, EveryChannelRefusesABadStepWithTheSameLine) {
  const Scene scene = plate();
  LiveSim<2> sim(scene, std::get<Mesh2>(load_mesh(scene)), viewer::initial_controls(scene, {}));
  for (const double dt :
       {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const std::string line = refusal([&] { checked_dt(dt); });
    EXPECT_EQ(line, "--dt must be a positive number") << dt;
    harness::RunOverrides run;
    run.dt = dt;
    EXPECT_EQ(refusal([&] { harness::with_overrides(scene, run); }), line) << dt;
    viewer::ViewOptions view;
    view.dt = dt;
    EXPECT_EQ(refusal([&] { viewer::initial_controls(scene, view); }), line) << dt;
    SimControls live = sim.controls();
    live.dt = dt;
    EXPECT_EQ(refusal([&] { sim.configure(live); }), line) << dt;
    EXPECT_GT(sim.controls().dt, 0.0) << "the stepper keeps its last good controls";
  }
}

} // namespace
} // namespace vtb
