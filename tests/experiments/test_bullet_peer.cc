// Bullet as a peer (experiments/peers, the harness's `bullet`): the stiffness fit and the
// stepper's fixed point.
#include "bullet_peer.hh"
#include "support/small_models.hh"
#include "vtb/harness/bullet.hh"
#include "vtb/solvers/simulation.hh"

#include <gtest/gtest.h>

namespace vtb {
namespace {

std::string clamped_plate(double young) {
  std::string text = test::pulled_plate(12, 3, "", "0.005, 0.002");
  const std::string from = "young_modulus = 5.0e4";
  text.replace(text.find(from), from.size(), "young_modulus = " + std::to_string(young));
  return text;
}

TEST(BulletPeer, FittedStiffnessScalesWithYoungsModulus) {
  // Under load control the FEM's displacement goes as 1/E, so the work W = f . u as 1/E and
  // the unit network's energy at that displacement as 1/E^2: k = (W / 2) / E_1 goes as E,
  // exactly for the linear FEM (to its solver's round-off, 1e-9 relative here).
  const Scene a = parse_scene(clamped_plate(5.0e4), "a.toml", ".");
  const Scene b = parse_scene(clamped_plate(1.0e5), "b.toml", ".");
  const Model<2> ma = build_model<2>(a, std::get<Mesh2>(load_mesh(a)));
  const Model<2> mb = build_model<2>(b, std::get<Mesh2>(load_mesh(b)));
  const double ka = harness::bullet_stiffness(a, ma), kb = harness::bullet_stiffness(b, mb);
  EXPECT_GT(ka, 0.0);
  EXPECT_NEAR(kb / ka, 2.0, 2e-9);
}

TEST(BulletPeer, ALoadFreeSceneIsRefused) {
  const Scene s = parse_scene(test::plate_scene(6, 2, "[[fix]]\ngroup = \"left\"\n"), "s.toml", ".");
  const Model<2> m = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  EXPECT_THROW(harness::bullet_stiffness(s, m), InputError);
}

TEST(BulletPeer, KeepsItsNetworksStaticStateAndRunsStably) {
  // The static state u* of the uniform network under the load is a fixed point of every
  // consistent step. u* by vtb's implicit Euler at a step of 10 s: backward Euler with a step
  // far beyond every time scale is Newton's method on F(u) = 0 (converged to round-off in the
  // 50 steps). Ten Bullet steps from (u*, 0) must then stay there: the residual at u* is round-
  // off (1e-12 of the loads), so the drift is of that order; 1e-9 of |u*| allows Bullet's
  // CG stopping tolerance (SIMD_EPSILON on a squared residual).
  const Scene s = parse_scene(clamped_plate(5.0e4), "s.toml", ".");
  Model<2> model = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  const double tau = s.material.retardation_time;
  const double k = harness::bullet_stiffness(s, model);
  Model<2> uniform = peers::uniform_network(model, k, tau * k);
  uniform.duration = 500.0;
  uniform.output_interval = uniform.duration;
  IntegratorOptions io;
  io.kind = solvers::kImplicitEuler;
  io.dt = 10.0;
  Trajectory<2> ie;
  ASSERT_TRUE(simulate(uniform, io, ie, true).stable);
  const Nodal<2> u_star = ie.field.back();
  ASSERT_GT(u_star.norm(), 0.0);

  peers::BulletOptions bo;
  bo.dt = 1e-3;
  bo.stiffness = k;
  bo.damping = tau * k;
  auto bullet = peers::make_bullet_integrator(uniform, bo);
  State<2> st = initial_state(uniform);
  st.t = 1.0; // the load is on
  st.u = u_star;
  for (int n = 0; n < 10; ++n) bullet->step(st);
  EXPECT_LT((st.u - u_star).norm(), 1e-9 * u_star.norm());

  // From rest, through the transient: a stable run whose displacement grows toward u*.
  uniform.duration = 0.5;
  uniform.output_interval = 0.05;
  io.kind = solvers::kBullet;
  io.dt = bo.dt;
  Trajectory<2> run;
  const RunReport r = simulate_with<2>(
      uniform, io, [&] { return peers::make_bullet_integrator(uniform, bo); }, run, true);
  ASSERT_TRUE(r.stable);
  EXPECT_GT(run.field.back().norm(), 0.1 * u_star.norm());
}

} // namespace
} // namespace vtb
