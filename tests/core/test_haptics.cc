// Haptics: force shaping, the watchdog on both faults, passivity of the virtual coupling
// against Colgate's bound, deterministic replay, and the proxy on convex and concave boundaries.
#include "support/small_models.hh"
#include "vtb/core/haptics/contact2d.hh"
#include "vtb/core/haptics/device.hh"
#include "vtb/core/haptics/force_shaping.hh"
#include "vtb/core/haptics/session.hh"
#include "vtb/meshes/cgal_generate.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace vtb {
namespace {

TEST(ForceShaping, SaturationKeepsDirectionAndRefusesNonFinite) {
  bool sat = false;
  const Eigen::Vector2d f = saturate({3.0, 4.0}, 2.0, &sat);
  EXPECT_TRUE(sat);
  EXPECT_NEAR(f.norm(), 2.0, 1e-15);
  EXPECT_NEAR(f.x() / f.y(), 0.75, 1e-15);
  EXPECT_EQ(saturate({1.0, 1.0}, 2.0), Eigen::Vector2d(1.0, 1.0));
  EXPECT_EQ(saturate({std::nan(""), 1.0}, 2.0), Eigen::Vector2d::Zero());
}

TEST(ForceShaping, RampsInAndOutAndStaysOff) {
  ForceShaper s(ForceShaper::Params{4.0, 0.5, 0.03, 0.01});
  const Eigen::Vector2d raw(1.0, 0.0);
  EXPECT_NEAR(s.shape(raw, 0.25, 0.25, true).x(), 0.5, 1e-15) << "half way through the 0.5 s ramp-in";
  EXPECT_NEAR(s.shape(raw, 1.0, 1.0, true).x(), 1.0, 1e-15);
  // Physics stops publishing at 1.0; called every millisecond as the servo does, the shaper
  // sees the stall at 1.011 (> 10 ms), then ramps to zero over 30 ms: zero from 1.041 on.
  double previous = 1.0;
  for (int k = 1; k <= 60; ++k) {
    const double t = 1.0 + 1e-3 * k;
    const double f = s.shape(raw, t, 1.0, true).x();
    if (t <= 1.0105) {
      EXPECT_EQ(f, 1.0) << t;
    }
    EXPECT_LE(f, previous) << t;
    if (t >= 1.0415) {
      EXPECT_EQ(f, 0.0) << t;
    }
    previous = f;
  }
  EXPECT_EQ(s.shape(raw, 2.0, 2.0, true).x(), 0.0) << "a tripped watchdog stays tripped";
}

Scene press_scene() {
  return read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments" / "scenes" / "haptic_press.toml");
}

class Watchdog : public ::testing::TestWithParam<std::string> {};

TEST_P(Watchdog, DropsTheForceToZeroWithin50msOfAFault) {
  // Lockstep (deterministic) press on the plate; the fault at 1.4 s, while the handle presses.
  HapticsOptions o;
  o.lockstep = true;
  o.fault = parse_fault(GetParam() + "@1.4", o.fault_time);
  const HapticsReport r = run_haptics(press_scene(), o);
  double before = 0;
  const ProbeTrace& p = r.probes.at(0);
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    const double f = std::hypot(p.fx[k], p.fy[k]);
    ASSERT_TRUE(std::isfinite(f)) << "t = " << r.t[k];
    ASSERT_LE(f, 4.0) << "t = " << r.t[k];
    if (r.t[k] < 1.4) before = std::max(before, f);
    if (r.t[k] >= 1.4 + 0.05) {
      ASSERT_EQ(f, 0.0) << "t = " << r.t[k];
    }
  }
  EXPECT_GT(before, 0.05) << "the handle was pressing when the fault came";
  EXPECT_GE(r.fault_time, 1.4);
  EXPECT_LE(r.force_zero_time, 1.4 + 0.05);
  EXPECT_EQ(r.nonfinite_samples, 0);
}

INSTANTIATE_TEST_SUITE_P(Faults, Watchdog, ::testing::Values("stall", "nan"));

TEST(Haptics, LockstepRunsAreDeterministicAndReplayReproducesTheHandle) {
  HapticsOptions o;
  o.lockstep = true;
  const Scene scene = press_scene();
  const HapticsReport a = run_haptics(scene, o), b = run_haptics(scene, o);
  ASSERT_EQ(a.t.size(), b.t.size());
  for (std::size_t k = 0; k < a.t.size(); ++k) {
    ASSERT_EQ(a.probes[0].fx[k], b.probes[0].fx[k]);
    ASSERT_EQ(a.probes[0].hy[k], b.probes[0].hy[k]);
  }
  // Record, then replay the handle: the replay device reports the recorded positions.
  const auto dir = std::filesystem::temp_directory_path() / "vtb_haptics_replay";
  write_haptics(a, dir, "press");
  ReplayDevice replay(DeviceSpec{}, dir / "haptics.csv");
  Eigen::Vector2d p, v;
  for (std::size_t k = 0; k + 1 < a.t.size(); k += 97) {
    replay.read(p, v);
    EXPECT_NEAR(p.y(), a.probes[0].hy[k], 1e-9) << "t = " << a.t[k];
    for (std::size_t j = 0; j < 97 && k + j + 1 < a.t.size(); ++j) replay.advance(a.t[k + j + 1] - a.t[k + j]);
  }
}

/// Peak-to-peak amplitude of the free handle on a sampled-and-held virtual spring F = -K x
/// (the coupling in contact, linearised), in the first and the last second of a 4 s run
/// started 2 mm off centre.
std::pair<double, double> bounce(double K, double b) {
  DeviceSpec spec;
  spec.max_force = 1e9;
  HandScript hand;
  hand.waypoints = {Eigen::Vector2d(0.002, 0.0)};
  hand.grip_stiffness = 0.0; // the hand lets go
  SimulatedProCAT::Physical phys;
  phys.viscous = b;
  phys.coulomb = 0;
  SimulatedProCAT dev(spec, hand, phys);
  const double T = 1e-3;
  double lo[2] = {1, 1}, hi[2] = {-1, -1};
  for (int k = 0; k < 4000; ++k) {
    const double x = dev.true_position().x();
    dev.command(Eigen::Vector2d(-K * x, 0.0)); // held for the whole period
    dev.advance(T);
    const int w = k < 1000 ? 0 : k >= 3000 ? 1 : -1;
    if (w >= 0) {
      lo[w] = std::min(lo[w], x);
      hi[w] = std::max(hi[w], x);
    }
  }
  return {hi[0] - lo[0], hi[1] - lo[1]};
}

TEST(Haptics, VirtualWallIsPassiveBelowColgatesBoundAndNotAbove) {
  // Colgate and Schenkel (1997): a sampled virtual spring K (period T, zero virtual damping)
  // on a device with physical damping b is passive iff b > K T / 2. With b = 0.5 N s/m and
  // T = 1 ms the bound is K < 1000 N/m: at K = 500 the oscillation dies out, at K = 4000 it
  // grows.
  const auto [p_first, p_last] = bounce(500.0, 0.5);
  EXPECT_LT(p_last, 0.1 * p_first) << "below the bound the wall dissipates";
  const auto [a_first, a_last] = bounce(4000.0, 0.5);
  EXPECT_GT(a_last, a_first) << "above the bound the wall injects energy";
}

TEST(Contact, ProxyStaysOnTheEntrySideOfAConvexBody) {
  // A 0.02 x 0.02 square pressed from the top deeper than half its height: the globally
  // closest boundary point would jump to the bottom edge; the proxy stays on top.
  const Mesh2 m = generate_rectangle({0.02, 0.02}, {4, 4});
  BoundaryContact c(m);
  const Nodal<2>& x = m.points;
  EXPECT_FALSE(c.update({0.01, 0.025}, x).touching);
  for (double y = 0.0199; y > 0.004; y -= 0.0005) {
    const auto r = c.update({0.01, y}, x);
    ASSERT_TRUE(r.touching) << y;
    ASSERT_NEAR(r.proxy.y(), 0.02, 1e-12) << "popped through at y = " << y;
  }
}

TEST(Contact, ProxySlidesAlongAConcaveCorner) {
  // An L-shaped plate (the notch is the square [0.02, 0.04]^2 removed): the handle enters the
  // horizontal notch edge and moves into the material under the notch; the proxy stays on the
  // boundary it touched or its neighbour and is never inside.
  Polygon L;
  L.vertices = {{0, 0}, {0.04, 0}, {0.04, 0.02}, {0.02, 0.02}, {0.02, 0.04}, {0, 0.04}};
  const Mesh2 m = mesh_polygon(L, 80);
  BoundaryContact c(m);
  EXPECT_FALSE(c.update({0.03, 0.025}, m.points).touching);
  auto r = c.update({0.03, 0.019}, m.points);
  ASSERT_TRUE(r.touching);
  EXPECT_NEAR(r.proxy.y(), 0.02, 1e-9);
  // Move left and down towards the re-entrant corner (0.02, 0.02), inside the material.
  for (double s = 0; s <= 1.0; s += 0.05) {
    r = c.update({0.03 - 0.012 * s, 0.019 - 0.004 * s}, m.points);
    ASSERT_TRUE(r.touching);
    const bool on_notch_bottom = std::abs(r.proxy.y() - 0.02) < 1e-9 && r.proxy.x() >= 0.02 - 1e-9;
    const bool on_notch_side = std::abs(r.proxy.x() - 0.02) < 1e-9 && r.proxy.y() >= 0.02 - 1e-9;
    EXPECT_TRUE(on_notch_bottom || on_notch_side) << r.proxy.transpose();
  }
}

} // namespace
} // namespace vtb
