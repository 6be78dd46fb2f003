// CVODE as the reference of the discrete spring model.
#include "support/small_models.hh"
#include "vtb/core/cvode_solver.hh"

#include <gtest/gtest.h>

#include <cmath>

namespace vtb {
namespace {

TEST(Cvode, SingleVoigtElementFollowsTheCreepLawToItsTolerance) {
  // m k / c^2 = 1e-8: the element obeys c x' + k x = F up to O(m / c) = 1e-7 s of transient.
  // CVODE's local error control at rtol 1e-9 keeps the global error near rtol x |x|; we allow
  // 1e-6 x F/k (the inertial correction, m F / c^2 ~ 2e-8 F/k relative, is far below).
  Model<2> model = test::single_element(100.0, 10.0, 1e-6, 2.0);
  model.duration = 0.5;
  model.output_interval = 0.05;
  Trajectory<2> tr;
  const RunReport r = simulate_cvode(model, CvodeOptions{1e-9, 1e-14}, tr, true);
  ASSERT_TRUE(r.stable) << r.failure;
  for (std::size_t k = 0; k < tr.t.size(); ++k)
    EXPECT_NEAR(tr.field[k](0, 1), 0.02 * (1 - std::exp(-10.0 * tr.t[k])), 1e-6 * 0.02) << "t = " << tr.t[k];
  for (const char* key : {"cvode_steps", "newton_iterations", "jacobian_evaluations", "error_test_failures"})
    EXPECT_TRUE(std::any_of(r.extra.begin(), r.extra.end(), [&](const auto& e) { return e.first == key; })) << key;
}

TEST(Cvode, ImplicitEulerConvergesToCvodeAtFirstOrder) {
  // A clamped plate under a step load with inertia and Voigt damping. CVODE at rtol 1e-10 is
  // the exact discrete-model trajectory to ~1e-9; implicit Euler's error against it must fall
  // by 2 when dt halves (order 1), and vanish as dt -> 0.
  Model<2> model = test::model_from(test::plate_scene(8, 2, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.2, 0.1]
)",
                                                      0.05));
  model.duration = 0.2;
  model.output_interval = 0.02;
  Trajectory<2> ref;
  ASSERT_TRUE(simulate_cvode(model, CvodeOptions{1e-10, 1e-15}, ref, true).stable);
  auto error = [&](double dt) {
    IntegratorOptions o;
    o.kind = "implicit-euler";
    o.dt = dt;
    Trajectory<2> tr;
    simulate(model, o, tr, true);
    double e = 0, scale = 0;
    for (std::size_t k = 0; k < ref.t.size(); ++k) {
      e = std::max(e, (tr.field[k] - ref.field[k]).norm());
      scale = std::max(scale, ref.field[k].norm());
    }
    return e / scale;
  };
  const double e1 = error(1e-3), e2 = error(5e-4), e3 = error(2.5e-4);
  EXPECT_NEAR(e2 / e3, 2.0, 0.2) << e1 << " " << e2 << " " << e3;
  EXPECT_LT(e3, e2);
  EXPECT_LT(e2, e1);
}

TEST(Cvode, NonFiniteStateIsAReportedFailureNotACrash) {
  // An initial velocity of 1e300 m/s makes the state overflow: CVODE must give up cleanly.
  Model<2> model = test::model_from(test::plate_scene(4, 1, "[initial]\nvelocity = [1e300, 0.0]\n"));
  model.duration = 0.1;
  model.output_interval = 0.01;
  Trajectory<2> tr;
  const RunReport r = simulate_cvode(model, CvodeOptions{1e-6, 1e-10}, tr);
  EXPECT_FALSE(r.stable);
  EXPECT_NE(r.failure.find("CVODE"), std::string::npos) << r.failure;
}

} // namespace
} // namespace vtb
