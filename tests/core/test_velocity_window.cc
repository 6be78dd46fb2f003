// The encoder's velocity by adaptive windowing (vtb/haptics/velocity_window.hh). Every bound
// below is the method's own: a window of n samples over quantised positions has a slope error
// of at most one count over n periods (each end within half a count of the true path).
#include "vtb/haptics/velocity_window.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace vtb;

namespace {
constexpr double kCount = 2e-6; // m, the ProCAT's encoder
constexpr double kT = 1e-3;     // s, the servo period
double quantised(double x) {
  return std::round(x / kCount) * kCount;
}
} // namespace

TEST(VelocityWindow, FollowsASteadyMotionWithTheLongestWindow) {
  AdaptiveWindowVelocity v(kCount);
  const double speed = 0.0137; // m/s: 6.85 counts a period, not a whole number
  for (int k = 0; k <= 100; ++k)
    v.add(k * kT, Eigen::Vector2d(quantised(speed * k * kT), quantised(-0.5 * speed * k * kT)));
  const double bound = kCount / (AdaptiveWindowVelocity::kMaxWindow * kT);
  EXPECT_NEAR(v.velocity().x(), speed, bound);
  EXPECT_NEAR(v.velocity().y(), -0.5 * speed, bound);
}

TEST(VelocityWindow, AHandleHeldAcrossACountBoundaryReadsAlmostStill) {
  // A first-order difference reads one count a period here (2 mm/s); the window reads at most
  // one count over its longest span.
  AdaptiveWindowVelocity v(kCount);
  std::mt19937 rng(7);
  std::bernoulli_distribution flip(0.4);
  double worst = 0;
  for (int k = 0; k < 400; ++k) {
    const double y = 25036e-6 + (flip(rng) ? kCount : 0.0);
    v.add(k * kT, Eigen::Vector2d(y, 0.02));
    if (k > AdaptiveWindowVelocity::kMaxWindow) worst = std::max(worst, std::abs(v.velocity().x()));
  }
  EXPECT_GT(worst, 0.0); // the flips are seen, only small
  EXPECT_LE(worst, kCount / (AdaptiveWindowVelocity::kMaxWindow * kT) * (1 + 1e-9));
}

TEST(VelocityWindow, ASuddenMotionShortensTheWindowToWhatFollowsIt) {
  // At rest, then 50 mm/s (25 counts a period): a window reaching back across the start misses
  // the corner by far more than a count, so m periods after the start the window is at most m
  // long and the slope is off by at most one count over m periods.
  AdaptiveWindowVelocity v(kCount);
  const double speed = 0.05;
  for (int k = 0; k <= 20; ++k) v.add(k * kT, Eigen::Vector2d::Constant(0.01));
  for (int m = 1; m <= 8; ++m) {
    v.add((20 + m) * kT, Eigen::Vector2d(quantised(0.01 + speed * m * kT), 0.01));
    EXPECT_NEAR(v.velocity().x(), speed, kCount / (m * kT) * (1 + 1e-9)) << m << " periods after the start";
    EXPECT_EQ(v.velocity().y(), 0.0);
  }
}
