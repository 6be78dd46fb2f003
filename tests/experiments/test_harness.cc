// The harness: error metrics on synthetic trajectories, compare end to end, the sweep's
// explicit stability boundary.
#include "support/small_models.hh"
#include "vtb/core/explicit_euler.hh"
#include "vtb/harness/compare.hh"
#include "vtb/harness/sweep.hh"

#include <gtest/gtest.h>

#include <cmath>

namespace vtb {
namespace {

Trajectory<2> synthetic(const std::vector<double>& t, double amplitude, double offset) {
  Trajectory<2> tr;
  for (double s : t) {
    tr.t.push_back(s);
    Nodal<2> f(2, 3);
    f << amplitude * s, 0, offset, 0, 0, amplitude * s;
    tr.field.push_back(f);
    tr.probe_u.push_back({Vec<2>(amplitude * s, 0.0)});
    tr.reaction.push_back({Vec<2>(-amplitude * s, offset)});
  }
  return tr;
}

TEST(Metrics, KnownErrorsOnSyntheticTrajectories) {
  // Reference field: two entries a t (a = 2) -> norm sqrt(2) a t, max sqrt(2) a at t = 1.
  // The run adds a constant 0.1 to one entry: e(t) = 0.1 / (sqrt(2) a) at every t.
  const std::vector<double> t = {0.0, 0.5, 1.0};
  const Trajectory<2> ref = synthetic(t, 2.0, 0.0), run = synthetic(t, 2.0, 0.1);
  const harness::ErrorMetrics m = harness::compare(run, ref);
  EXPECT_NEAR(m.displacement_max, 0.1 / (std::sqrt(2.0) * 2.0), 1e-15);
  EXPECT_NEAR(m.displacement_final, 0.1 / (std::sqrt(2.0) * 2.0), 1e-15);
  EXPECT_EQ(m.probe_max, 0.0);
  EXPECT_NEAR(m.reaction_max, 0.1 / 2.0, 1e-15);
  EXPECT_EQ(m.compared, 3u);
  // A run twice as large: error |a t| / (sqrt 2 a) per time, max 1 at t = 1.
  EXPECT_NEAR(harness::compare(synthetic(t, 4.0, 0.0), ref).displacement_max, 1.0, 1e-15);
  // Mismatched sample times are refused.
  EXPECT_THROW(harness::compare(synthetic({0.0, 0.6, 1.0}, 2.0, 0.0), ref), std::invalid_argument);
}

TEST(Compare, RunsTheDecompositionOnASmallPlate) {
  const Scene scene = parse_scene(test::plate_scene(8, 2, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.2, 0.0]
[solver]
dt = 0.01
)"),
                                  "plate.toml", ".");
  Scene s = scene;
  s.duration = 0.2;
  s.output_interval = 0.02;
  const auto res = harness::run_compare(s, {"filtered-full", "implicit-euler", "cvode"}, "fem");
  ASSERT_EQ(res.rows.size(), 4u);
  ASSERT_EQ(res.decomposition.size(), 3u);
  for (const auto& row : res.rows) EXPECT_TRUE(row.report.stable) << row.solver;
  // The reference against itself is exact; every other error is finite and below 100 %.
  EXPECT_EQ(res.rows.back().error.displacement_max, 0.0);
  for (const auto& row : res.rows) EXPECT_LT(row.error.displacement_max, 1.0) << row.solver;
  // The decomposition's three terms are present, in order, and the time error is non-zero.
  EXPECT_GT(res.decomposition[0].error.displacement_max, 0.0);
  EXPECT_EQ(res.decomposition[1].a, "cvode");
  EXPECT_EQ(res.decomposition[1].b, "fem");
}

TEST(Sweep, FindsTheExplicitBoundaryWithinTwentyPercentOfThePrediction) {
  // Undamped tiny plate: the predicted limit 2 / omega_max is exact for the linear problem;
  // the sweep's boundary (largest stable dt, smallest unstable dt) must bracket it within 20 %.
  Scene s = parse_scene(test::plate_scene(4, 1, "[[fix]]\ngroup = \"left\"\n", 0.0), "tiny.toml", ".");
  s.duration = 0.2;
  s.output_interval = 0.01;
  const Model<2> model = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  const double predicted = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  // The model starts at rest without load: perturb it with a tiny initial velocity, and run
  // about 2000 steps so that a mode growing by >= 10 % per step (1.05x the limit) passes the
  // 1000 % strain criterion from 1e-6.
  s.initial_velocity = Eigen::Vector2d(1e-6, 1e-6);
  s.duration = 2000 * predicted;
  s.output_interval = s.duration / 20;
  std::vector<double> dts;
  for (double f = 0.5; f <= 1.6; f += 0.1) dts.push_back(f * predicted);
  const auto cells = harness::run_sweep(s, dts, {1.0}, {"explicit"});
  double stable_max = 0, unstable_min = 1e9;
  for (const auto& c : cells)
    (c.stable ? stable_max : unstable_min) = c.stable ? std::max(stable_max, c.dt) : std::min(unstable_min, c.dt);
  EXPECT_GT(stable_max, 0.8 * predicted);
  EXPECT_LT(unstable_min, 1.2 * predicted);
  EXPECT_LE(stable_max, unstable_min);
  EXPECT_NEAR(cells.front().courant_dt, predicted, 1e-9 * predicted);
}

} // namespace
} // namespace vtb
