// Integrators against analytic cases: creep of one Voigt element, a clamped strip's static
// stretch, momentum of a free body, the explicit Courant limit, the filtered scheme at
// large steps.
#include "support/small_models.hh"
#include "vtb/meshes/region.hh"
#include "vtb/solvers/cvode_solver.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"
#include "vtb/solvers/simulation.hh"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>

namespace vtb {
namespace {

IntegratorOptions opts(const std::string& kind, double dt, const std::string& filter = "full", bool correct = true) {
  IntegratorOptions o;
  o.kind = kind;
  o.dt = dt;
  o.filter = filter;
  o.momentum_correction = correct;
  o.strain_limit = 0;
  return o;
}

/// Max over [0, T] of |x(t) - F/k (1 - exp(-k t / c))| for the single element.
double creep_error(const std::string& kind, const std::string& filter, double dt) {
  const double k = 100.0, c = 10.0, m = 1e-6, F = 2.0, T = 0.5; // creep time c/k = 0.1 s
  Model<2> model = test::single_element(k, c, m, F);
  auto integ = make_integrator(model, opts(kind, dt, filter));
  State<2> s = initial_state(model);
  double err = 0;
  while (s.t < T - 1e-12) {
    integ->step(s);
    err = std::max(err, std::abs(s.u(0, 1) - F / k * (1 - std::exp(-k * s.t / c))));
    EXPECT_NEAR(s.u(1, 1), 0.0, 1e-15);
  }
  return err;
}

class Creep : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(Creep, SingleVoigtElementFollowsTheCreepLaw) {
  // With negligible mass (m k / c^2 = 1e-8) the element obeys c x' + k x = F, whose solution
  // is x = F/k (1 - exp(-t/tau)), tau = c/k. Backward Euler's global error is first order:
  // |e| <= dt/(2 tau) * max_t (t/tau) e^(-t/tau) * F/k * (1 + O(dt/tau)) <= dt/(2 e tau) F/k
  // (3.68e-5 here, measured 3.66e-5); we allow the first-order correction, a factor
  // 1 + dt/tau. On one free node the filter is 1x1 and is implicit Euler, so all three agree.
  // Halving dt: e(dt) = A dt + B dt^2 with B/A ~ 1/tau, so the ratio is 2 (1 + dt/(2 tau))
  // to first order: 2 within 2 dt/tau = 0.02.
  const auto& [kind, filter] = GetParam();
  const double tau = 0.1, Fk = 0.02, dt = 1e-3;
  const double e1 = creep_error(kind, filter, dt), e2 = creep_error(kind, filter, dt / 2);
  EXPECT_LT(e1, dt / (2 * std::exp(1.0) * tau) * Fk * (1 + dt / tau));
  EXPECT_NEAR(e1 / e2, 2.0, 2 * dt / tau);
}

INSTANTIATE_TEST_SUITE_P(ImplicitSchemes, Creep,
                         ::testing::Values(std::make_pair("implicit-euler", "full"), std::make_pair("filtered", "full"),
                                           std::make_pair("filtered", "neighbors")),
                         [](const auto& pinfo) {
                           std::string n = pinfo.param.first + "_" + pinfo.param.second;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

/// Static tip stretch (mean x displacement of the loaded end) of a clamped strip.
double strip_stretch(double length, double width, double force, const std::string& springs, double* e_eff_t) {
  const double h = 0.005; // square cells
  const std::string text =
      test::plate_scene(static_cast<int>(std::lround(length / h)), static_cast<int>(std::lround(width / h)), R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [)" + std::to_string(force) + R"(, 0.0]
[solver]
springs = ")" + springs + "\"\n",
                        0.05, std::to_string(length) + ", " + std::to_string(width), 20.0);
  Model<2> model = test::model_from(text);
  // Backward Euler with a long step and mass damping walks to the static state.
  model.duration = 20.0;
  model.output_interval = model.duration;
  Trajectory<2> tr;
  const RunReport r = simulate(model, opts("implicit-euler", 0.05), tr, true);
  EXPECT_TRUE(r.stable);
  double tip = 0;
  const auto& right = model.mesh.groups.at("right").nodes;
  for (int i : right) tip += tr.field.back()(0, i) / static_cast<double>(right.size());
  // The union-jack lattice (square cells, one diagonal each) deforms affinely under uniform
  // strain (every node is a centre of symmetry), so its bulk moduli follow from the interior
  // spring constants: C11 = C22 = k_axis + k_diag / 2, C12 = k_diag / 2 (per thickness:
  // N/m), and the uniaxial modulus is E_eff t = C11 - C12^2 / C22.
  const auto& net = model.net;
  double k_axis = 0, k_diag = 0;
  for (int sp = 0; sp < net.num_springs(); ++sp) {
    const Eigen::Vector2d d = net.rest.col(net.edge[static_cast<std::size_t>(sp)][1]) -
                              net.rest.col(net.edge[static_cast<std::size_t>(sp)][0]);
    if (std::abs(d.y()) < 1e-12)
      k_axis = std::max(k_axis, net.stiffness[sp]);
    else if (std::abs(d.x()) > 1e-12)
      k_diag = std::max(k_diag, net.stiffness[sp]);
  }
  const double c11 = k_axis + k_diag / 2, c12 = k_diag / 2;
  *e_eff_t = c11 - c12 * c12 / c11;
  return tip;
}

class Strip : public ::testing::TestWithParam<std::string> {};

TEST_P(Strip, StretchesByFLOverEffectiveEA) {
  // Continuum: a strip stretches by F L / (E A). Two lattice effects are removed exactly:
  // - the clamp's boundary layer decays like exp(-pi x / W) (Saint-Venant) and is the same for
  //   two lengths, so the stretch difference of L = 0.4 and 0.2 is F dL / K, with K the axial
  //   stiffness per length of the strip;
  // - the free edges add a fixed stiffness per length each, so K(W) = E_eff t W + 2 s_edge is
  //   linear in the width and (K(0.08) - K(0.04)) / 0.04 is the bulk E_eff t.
  // What remains: the strain (~1e-5) times O(1) geometric nonlinearity (~1e-5), the static
  // residual (< 1e-8), and the interaction of the two edge layers, which decays exponentially
  // with the rows between them: 9.0e-4 (lloyd) with widths of 4 and 8 rows, 3e-5 and 1e-5
  // (lloyd, van Gelder) with 8 and 16 rows, i.e. a factor >= 30 per doubling. We allow 1e-4:
  // the 4/8-row value divided by that factor (3e-5) plus the nonlinearity, with a factor 2.
  // The calibration's own error is E_eff / E, printed, and exact for van Gelder.
  const std::string springs = GetParam();
  const double F = 5e-6;
  double e_t = 0, e_other = 0;
  auto stiffness = [&](double width) {
    const double dtip = strip_stretch(0.4, width, F, springs, &e_other) - strip_stretch(0.2, width, F, springs, &e_t);
    EXPECT_NEAR(e_t, e_other, 1e-12 * e_t);
    return F * 0.2 / dtip;
  };
  const double bulk = (stiffness(0.08) - stiffness(0.04)) / 0.04;
  EXPECT_NEAR(bulk, e_t, 1e-4 * e_t);
  const double ratio = e_t / (5.0e4 * 0.001);
  std::cout << springs << ": E_eff / E = " << ratio << " on the union-jack lattice, measured " << bulk / (5.0e4 * 0.001)
            << "\n";
  if (springs == "van-gelder") {
    EXPECT_NEAR(ratio, 1.2, 1e-12) << "k_axis = E t, k_diag = E t / 2 => 1.25 - 0.05";
  }
}

INSTANTIATE_TEST_SUITE_P(Calibrations, Strip, ::testing::Values("lloyd", "van-gelder"), [](const auto& pinfo) {
  return pinfo.param == "lloyd" ? std::string("lloyd") : std::string("van_gelder");
});

struct MomentumCase {
  std::string kind, filter;
  bool correct;
};

std::ostream& operator<<(std::ostream& os, const MomentumCase& c) {
  return os << c.kind << " " << c.filter << (c.correct ? " corrected" : "");
}

class FreeBody : public ::testing::TestWithParam<MomentumCase> {};

TEST_P(FreeBody, KeepsLinearAndAngularMomentum) {
  // A free plate thrown with velocity and spin, no loads. Internal forces are central pairs,
  // so the exact discrete dynamics keep both momenta; see each integrator's expectation.
  const auto& c = GetParam();
  Model<2> model =
      test::model_from(test::plate_scene(8, 2, "[initial]\nvelocity = [0.1, -0.05]\nangular_velocity = 2.0\n"));
  // Explicit and the neighbour filter run at half the explicit limit, the full filter at 1 ms.
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), 0.05, 0.0);
  const double dt = (c.kind == "filtered" && c.filter != "neighbors") ? 1e-3 : 0.5 * dtc;
  auto integ = make_integrator(model, opts(c.kind, dt, c.filter, c.correct));
  State<2> s = initial_state(model);
  const Eigen::Vector2d p0 = test::momentum(model, s);
  double scale = 0;
  const double l0 = test::angular_momentum(model, s, &scale);
  // Linear momentum: every scheme here but the uncorrected neighbour filter is exact up to
  // round-off (that one truncates W = H^-1, whose columns, weighted by the masses, sum to one;
  // the truncated W's do not, so it drifts: 1.7e-12 here, 1.6e-9 of p0, and the correction
  // removes it with the torque). The round-off's size (Higham's bound for
  // a sum, (n - 1) eps sum |x_i|): each step rounds every v_i += dv_i (eps m |v|) and makes
  // each dv_i from a node's sum of up to `degree` spring terms, passed through the filter
  // (`degree` eps m |dv| more), so |p - p0| <= eps sum_steps sum_i m_i (|v_i| + degree |dv_i|).
  int degree = 0;
  for (int i = 0; i < model.num_nodes(); ++i)
    degree = std::max(degree, model.net.adj_ptr[static_cast<std::size_t>(i) + 1] -
                                  model.net.adj_ptr[static_cast<std::size_t>(i)]);
  double traffic = 0;
  for (int k = 0; k < 200; ++k) {
    const Nodal<2> v = s.v;
    integ->step(s);
    for (int i = 0; i < model.num_nodes(); ++i)
      traffic += model.net.mass[i] * (s.v.col(i).norm() + degree * (s.v.col(i) - v.col(i)).norm());
  }
  const double eps = std::numeric_limits<double>::epsilon();
  if (c.kind != "filtered" || c.filter != "neighbors" || c.correct) {
    EXPECT_LT((test::momentum(model, s) - p0).norm(), eps * traffic);
  }
  const double dl = std::abs(test::angular_momentum(model, s) - l0) / scale;
  if (c.kind == "explicit" || c.correct) {
    EXPECT_LT(dl, 1e-10) << "exact: central forces, and the correction removes the filter's torque";
  } else if (c.kind == "filtered") {
    EXPECT_GT(dl, 1e-8) << "without the correction the neighbour filter does change the spin (far above round-off)";
  }
}

INSTANTIATE_TEST_SUITE_P(Schemes, FreeBody,
                         ::testing::Values(MomentumCase{"explicit", "", false}, MomentumCase{"filtered", "full", true},
                                           MomentumCase{"filtered", "tensor", true},
                                           MomentumCase{"filtered", "neighbors", true},
                                           MomentumCase{"filtered", "neighbors", false}),
                         [](const auto& pinfo) {
                           std::string n =
                               pinfo.param.kind + "_" + pinfo.param.filter + (pinfo.param.correct ? "_corrected" : "");
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(Integrators, TensorFilterKeepsASpinningPlatesAngularVelocityByWarping) {
  // A free plate spinning at 2 rad/s for one revolution (pi s) at dt = 1 ms, without the
  // momentum correction: the rest Jacobian's blocks are anisotropic, so unwarped they would
  // act in the wrong frame once the plate has turned; warped (each node's force rotated into
  // its rest frame and back) the filter sees the body as at rest. The goal: the angular
  // velocity L / I within 2 % after the revolution.
  Model<2> model = test::model_from(test::plate_scene(8, 2, "[initial]\nangular_velocity = 2.0\n"));
  auto omega = [&](const State<2>& s) {
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    double mass = 0;
    for (int i = 0; i < model.num_nodes(); ++i) {
      c += model.net.mass[i] * (model.net.rest.col(i) + s.u.col(i));
      mass += model.net.mass[i];
    }
    c /= mass;
    double l = 0, inertia = 0;
    for (int i = 0; i < model.num_nodes(); ++i) {
      const Eigen::Vector2d r = model.net.rest.col(i) + s.u.col(i) - c;
      l += model.net.mass[i] * (r.x() * s.v(1, i) - r.y() * s.v(0, i));
      inertia += model.net.mass[i] * r.squaredNorm();
    }
    return l / inertia;
  };
  auto integ = make_integrator(model, opts("filtered", 1e-3, "tensor", false));
  State<2> s = initial_state(model);
  const double w0 = omega(s);
  while (s.t < M_PI - 1e-9) integ->step(s);
  std::cout << "tensor filter: angular velocity after one revolution " << omega(s) / w0 << " of the start\n";
  EXPECT_NEAR(omega(s) / w0, 1.0, 0.02);
}

TEST(Integrators, ImplicitEulerAngularMomentumDriftIsFirstOrder) {
  // Linearised backward Euler is not a symmetry-preserving scheme: a spinning body loses
  // angular momentum at a rate O(dt). Halving dt over the same time halves the loss.
  Model<2> model = test::model_from(test::plate_scene(8, 2, "[initial]\nangular_velocity = 5.0\n"));
  auto drift = [&](double dt) {
    auto integ = make_integrator(model, opts("implicit-euler", dt));
    State<2> s = initial_state(model);
    const double l0 = test::angular_momentum(model, s);
    while (s.t < 0.2 - 1e-12) integ->step(s);
    return std::abs(test::angular_momentum(model, s) - l0) / l0;
  };
  // Measured ratios d(2h)/d(h) for h = 2, 1, 0.5, 0.25, 0.125 ms: 2.96, 2.64, 2.38, 2.19, 2.09:
  // first order, with an O(dt) correction from the stretch oscillation that is still ~5 % at
  // h = 62.5 us. We check the asymptotic regime: ratio 2 within 0.15.
  const double d1 = drift(1.25e-4), d2 = drift(6.25e-5);
  EXPECT_NEAR(d1 / d2, 2.0, 0.15);
}

/// Runs the explicit scheme on a clamped plate from a small random velocity and reports
/// whether it stayed bounded.
bool explicit_bounded(const Model<2>& model, double dt, int steps) {
  auto integ = make_integrator(model, opts("explicit", dt));
  State<2> s = initial_state(model);
  s.v.setRandom();
  s.v *= 1e-6;
  model.apply_constraints(0, s.u, s.v);
  const double e0 = s.v.norm();
  for (int k = 0; k < steps; ++k) integ->step(s);
  return s.v.allFinite() && s.v.norm() < 100 * e0;
}

class Courant : public ::testing::TestWithParam<double> {}; // param: retardation time tau

TEST_P(Courant, ExplicitIsStableJustBelowThePredictedStepAndUnstableJustAbove) {
  // Linear stability of symplectic Euler for a mode omega^2 with Voigt damping rate tau w^2:
  // dt^2 w^2 + 2 tau w^2 dt < 4. With the exact largest w^2 the boundary is sharp: at 1.05x
  // the worst mode grows by a factor >= 1.2 per step (here 2000 steps), at 0.95x none grows.
  const double tau = GetParam();
  const Model<2> model = test::model_from(test::plate_scene(8, 2, "[[fix]]\ngroup = \"left\"\n", tau));
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), tau, 0.0);
  EXPECT_TRUE(explicit_bounded(model, 0.95 * dtc, 2000));
  EXPECT_FALSE(explicit_bounded(model, 1.05 * dtc, 2000));
}

INSTANTIATE_TEST_SUITE_P(UndampedAndDamped, Courant, ::testing::Values(0.0, 1e-4),
                         [](const auto& pinfo) { return pinfo.param == 0.0 ? "undamped" : "damped"; });

TEST(Courant, TheCheapEstimateIsARayleighQuotientOfTheExactOperator) {
  // The run's estimate (power iteration, S applied spring by spring) is a Rayleigh quotient of
  // S = M^-1/2 K M^-1/2, so at most the exact largest eigenvalue (up to round-off); and after
  // 400 iterations it has converged on these small meshes. A wrong block (a sign, a missing
  // scale, a fixed end moved) gives an operator with another spectrum and misses both bounds.
  const Model<2> plate = test::model_from(test::plate_scene(8, 2, "[[fix]]\ngroup = \"left\"\n"));
  const Model<2> free = test::model_from(test::plate_scene(6, 3, ""));
  const double exact_plate = max_omega_squared(plate, true), exact_free = max_omega_squared(free, true);
  const double cheap_plate = max_omega_squared(plate, false), cheap_free = max_omega_squared(free, false);
  EXPECT_LE(cheap_plate, exact_plate * (1 + 1e-12));
  EXPECT_LE(cheap_free, exact_free * (1 + 1e-12));
  // Convergence: the quotient's error falls like (w2/w1)^(2k) for the two largest eigenvalues;
  // here it is within 1e-5 (clamped) and 4e-4 (free, a closer pair) of exact, inside the 1 %
  // that the run's courant_dt_estimate promises.
  EXPECT_GE(cheap_plate, 0.99 * exact_plate);
  EXPECT_GE(cheap_free, 0.99 * exact_free);
}

TEST(Integrators, FilteredIsStableAtAHundredTimesTheExplicitStep) {
  // The full filter is linearised backward Euler with a scalar Laplacian: unconditionally
  // stable for the linear problem; the multigrid filter is the same with extra mass. A clamped
  // plate under a step load at 100x the Courant step must stay bounded and settle on the same
  // static state as implicit Euler (all are fixed points of F_int + F_ext = 0), to 1e-6
  // relative after the transient has decayed. 451 nodes: a three-level multigrid hierarchy.
  const std::string text = test::plate_scene(40, 10, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.2, 0.05]
)",
                                             0.0);
  Model<2> model = test::model_from(text);
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  model.net.mass_damping = 0; // undamped: the hardest case for stability
  const double dt = 100 * dtc;
  model.duration = 6000 * dt;
  model.output_interval = model.duration;
  Trajectory<2> b;
  ASSERT_TRUE(simulate(model, opts("implicit-euler", dt), b, true).stable);
  for (const char* filter : {solvers::kFilterFull, solvers::kFilterMultigrid}) {
    Trajectory<2> a;
    ASSERT_TRUE(simulate(model, opts("filtered", dt, filter), a, true).stable) << filter;
    EXPECT_LT((a.field.back() - b.field.back()).norm(), 1e-6 * b.field.back().norm()) << filter;
  }
}

/// Runs the undamped model with the neighbour filter for 2000 steps at each multiple of the
/// explicit (Courant) step: stable at 1x, divergent at every larger multiple.
template <int dim>
void expect_neighbour_filter_stable_only_at_the_explicit_step(Model<dim> model, std::initializer_list<double> mults) {
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  for (double mult : mults) {
    model.duration = 2000 * mult * dtc;
    model.output_interval = model.duration / 20;
    Trajectory<dim> tr;
    const RunReport r = simulate(model, opts("filtered", mult * dtc, "neighbors"), tr);
    EXPECT_EQ(r.stable, mult == 1.0) << "at " << mult << "x the explicit step";
  }
}

TEST(Integrators, NeighbourFilterDivergesBeyondAFewExplicitSteps) {
  // The paper's truncated filter is conditionally stable (see FilterMatrix tests): on the
  // undamped 16x4 plate the spectral radius of its linearised step is below 1 at the explicit
  // step and above 1 from twice it (docs/method.md), so the run is stable at 1x and diverges
  // at 2x (and at 10x). Recorded, not hidden.
  const std::string text = test::plate_scene(
      16, 4, "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.2, 0.0]\n", 0.0);
  Model<2> model = test::model_from(text);
  expect_neighbour_filter_stable_only_at_the_explicit_step(model, {1.0, 2.0, 10.0});
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(Integrators3D, SpinningFreeBoxKeepsMomentaWithTheFilter) {
  // The same code in 3D: a free box thrown with velocity and spin about a tilted axis. The
  // full filter with the momentum correction keeps P and L = sum m x x v to round-off.
  Scene s = parse_scene(R"(
[scene]
duration = 0.05
output_interval = 0.01
[mesh]
generate = { shape = "box", size = [0.1, 0.05, 0.04], divisions = [4, 2, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.25
density = 1000.0
retardation_time = 0.02
[initial]
velocity = [0.1, 0.0, -0.2]
angular_velocity = [1.0, 2.0, 3.0]
)",
                        "box.toml", ".");
  const Model<3> model = build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
  auto momenta = [&](const State<3>& st, Eigen::Vector3d& p, Eigen::Vector3d& l, double& scale) {
    p.setZero();
    l.setZero();
    scale = 0;
    for (int i = 0; i < model.num_nodes(); ++i) {
      const Eigen::Vector3d x = model.net.rest.col(i) + st.u.col(i);
      p += model.net.mass[i] * st.v.col(i);
      l += model.net.mass[i] * x.cross(Eigen::Vector3d(st.v.col(i)));
      scale += model.net.mass[i] * x.norm() * st.v.col(i).norm();
    }
  };
  IntegratorOptions o;
  o.kind = "filtered";
  o.dt = 1e-3;
  auto integ = make_integrator(model, o);
  State<3> st = initial_state(model);
  Eigen::Vector3d p0, l0, p1, l1;
  double scale = 0;
  momenta(st, p0, l0, scale);
  for (int k = 0; k < 100; ++k) integ->step(st);
  momenta(st, p1, l1, scale);
  EXPECT_LT((p1 - p0).norm(), 1e-12 * scale);
  EXPECT_LT((l1 - l0).norm(), 1e-10 * scale);
}

TEST(Integrators3D, ClampedBoxSettlesOnTheSameStaticStateWithEachImplicitScheme) {
  Scene s = parse_scene(R"(
[scene]
duration = 10.0
output_interval = 10.0
[mesh]
generate = { shape = "box", size = [0.1, 0.03, 0.03], divisions = [6, 2, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.25
density = 1000.0
retardation_time = 0.02
mass_damping = 20.0
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.0, -0.01, 0.005]
)",
                        "box.toml", ".");
  const Model<3> model = build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
  IntegratorOptions o;
  o.dt = 5e-3;
  Trajectory<3> a, b;
  o.kind = "filtered";
  ASSERT_TRUE(simulate(model, o, a, true).stable);
  o.kind = "implicit-euler";
  ASSERT_TRUE(simulate(model, o, b, true).stable);
  // Both are fixed points of F_int + F_ext = 0. The filter's scalar H = M + dt^2 K_L charges
  // the soft bending modes with the stiffness of the Laplacian, an artificial inertia that
  // slows their approach to rest (after 1 s the two still differed by 1.6 %); after 10 s
  // with mass damping 20/s both transients are far below 1e-4 of the deflection.
  // Reactions balance the load.
  EXPECT_LT((a.field.back() - b.field.back()).norm(), 1e-4 * b.field.back().norm());
  EXPECT_LT((b.reaction.back()[0] + Eigen::Vector3d(0.0, -0.01, 0.005)).norm(), 1e-4 * 0.01);
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

struct DriveCase {
  std::string kind, filter;
};
std::ostream& operator<<(std::ostream& os, const DriveCase& c) {
  return os << c.kind << " " << c.filter;
}

class EverySolver : public ::testing::TestWithParam<DriveCase> {};

/// A plate clamped on the left whose right-edge midpoint is driven (ramped) to a prescribed
/// displacement, with mass damping 20/s so that it settles.
Model<2> driven_plate() {
  Model<2> model = test::model_from(test::plate_scene(8, 2, R"(
[[fix]]
name = "clamp"
group = "left"
[[drive]]
name = "probe"
point = [0.2, 0.025]
displacement = [0.002, -0.001]
start = 0.0
ramp = 0.2
)",
                                                      0.02, "0.2, 0.05", 20.0));
  model.duration = 2.0;
  model.output_interval = 0.1;
  return model;
}

TEST_P(EverySolver, HonoursADriveAndBalancesItsReactionAtRest) {
  // Every spring solver holds the driven node exactly on its prescribed path, and all settle
  // on the one static state, where the drive's and the clamp's reactions cancel. After the
  // ramp (0.2 s) the slowest mode decays at least like exp(-gamma t / 2) with gamma = 20/s:
  // exp(-18) ~ 2e-8 of the reaction by t = 2 s; we allow 1e-6 of it, for the balance and for
  // the agreement with implicit Euler's static reaction.
  const auto& c = GetParam();
  const Model<2> model = driven_plate();
  IntegratorOptions o = opts(c.kind, 1e-3, c.filter);
  if (c.kind == "explicit" || c.filter == "neighbors")
    o.dt = 0.5 * explicit_critical_dt(max_omega_squared(model, true), 0.02, 20.0);
  Trajectory<2> tr;
  const RunReport r =
      c.kind == "cvode" ? simulate_cvode(model, CvodeOptions{}, tr, true) : simulate(model, o, tr, true);
  ASSERT_TRUE(r.stable) << r.failure;
  // Samples are interpolated linearly within their step: exact on the linear ramp and after
  // it, off by at most the ramp's rate times one step where a step straddles its end (0.2 s).
  const int node = model.supports[1].nodes.at(0);
  const double step = c.kind == "cvode" ? 0.0 : o.dt;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    const double f = ramp_factor(tr.t[k], 0.0, 0.2);
    const double tol = std::abs(tr.t[k] - 0.2) < step ? step / 0.2 : 1e-15;
    ASSERT_NEAR(tr.field[k](0, node), 0.002 * f, 0.002 * tol + 1e-15) << "t = " << tr.t[k];
    ASSERT_NEAR(tr.field[k](1, node), -0.001 * f, 0.001 * tol + 1e-15) << "t = " << tr.t[k];
  }
  const Vec<2> clamp = tr.reaction.back()[0], drive = tr.reaction.back()[1];
  EXPECT_GT(drive.norm(), 1e-3) << "the drive pulls";
  EXPECT_LT((clamp + drive).norm(), 1e-6 * drive.norm());
  Trajectory<2> ie;
  simulate(model, opts("implicit-euler", 1e-3), ie, false);
  EXPECT_LT((drive - ie.reaction.back()[1]).norm(), 1e-6 * drive.norm());
}

INSTANTIATE_TEST_SUITE_P(Solvers, EverySolver,
                         ::testing::Values(DriveCase{"explicit", "full"}, DriveCase{"filtered", "full"},
                                           DriveCase{"filtered", "neighbors"}, DriveCase{"implicit-euler", "full"},
                                           DriveCase{"cvode", "full"}),
                         [](const auto& pinfo) {
                           std::string n = pinfo.param.kind + "_" + pinfo.param.filter;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

class StrainLimit : public ::testing::TestWithParam<std::string> {};

TEST_P(StrainLimit, ProjectsAnOverstretchedSpringToTheLimitInOneStep) {
  // One Voigt element, node 0 fixed, node 1 free and held at 50 % stretch with no velocity.
  // One step of 1 us moves node 1 by O(dt^2 k/m x) ~ 1e-10 of L; then the post-step pass
  // (Provot 1995) moves the free end back onto (1 + limit) L0 = 1.1 exactly and gives it the
  // velocity of that move over dt. Without the limit the spring stays at 1.5.
  const std::string filter = GetParam();
  const Model<2> model = test::single_element(1.0, 0.0, 1.0, 0.0);
  for (double limit : {0.0, 0.1}) {
    IntegratorOptions o = opts("filtered", 1e-6, filter);
    o.strain_limit = limit;
    auto integ = make_integrator(model, o);
    State<2> s = initial_state(model);
    s.u(0, 1) = 0.5;
    integ->step(s);
    const double l = (model.net.rest.col(1) + s.u.col(1) - model.net.rest.col(0)).norm();
    if (limit > 0) {
      EXPECT_NEAR(l, 1.1, 1e-12);
      EXPECT_NEAR(s.v(0, 1), (1.1 - 1.5) / 1e-6, 1e-3) << "the projection's velocity, -4e5 m/s";
    } else {
      EXPECT_NEAR(l, 1.5, 1e-9);
    }
  }
}

TEST_P(StrainLimit, LowersTheStretchOfAFastPull) {
  // A plate's corner driven 1.5 cm in 0.01 s (a 7.5 % mean stretch of the top edge, so a
  // 10 % cap is feasible): unlimited, the corner's springs reach about 20 %. One projection
  // pass per step cannot hold every spring at the cap (a later projection stretches an earlier
  // spring again through the node they share), so what is asserted is that the pass lowers
  // the worst stretch, not that it removes the excess. Lloyd's springs, named: the 20 % and
  // the pass's effect were measured on them (the fitted 8 x 2 plate, whose fit its 27 nodes
  // barely determine, reaches 28 % free and the single pass does not lower it).
  const std::string filter = GetParam();
  Model<2> model = test::model_from(test::plate_scene(8, 2, R"(
[solver]
springs = "lloyd"
[[fix]]
group = "left"
[[drive]]
point = [0.2, 0.05]
displacement = [0.015, 0.0]
ramp = 0.01
)",
                                                      0.02));
  model.duration = 0.2;
  model.output_interval = 0.01;
  IntegratorOptions o = opts("filtered", 1e-3, filter);
  if (filter == "neighbors") o.dt = 0.5 * explicit_critical_dt(max_omega_squared(model, true), 0.02, 0.0);
  Trajectory<2> free, limited;
  const RunReport a = simulate(model, o, free);
  o.strain_limit = 0.1;
  const RunReport b = simulate(model, o, limited);
  ASSERT_TRUE(b.stable) << b.failure;
  std::cout << filter << ": max strain " << a.max_strain << " free, " << b.max_strain << " limited to 0.1\n";
  EXPECT_GT(a.max_strain, 0.15);
  EXPECT_LT(b.max_strain, a.max_strain - 0.25 * (a.max_strain - 0.1));
}

INSTANTIATE_TEST_SUITE_P(Filters, StrainLimit, ::testing::Values("full", "neighbors"));

} // namespace
} // namespace vtb

namespace vtb {
namespace {

/// The clamped 6 x 2 x 2 box with Lloyd's springs (named: the fitted network's softer lowest
/// mode decays more slowly, and the 4000-step settling below was sized on Lloyd's).
Model<3> clamped_box(double tau, const std::string& springs = "lloyd", double nu = 0.25) {
  const Scene s = parse_scene(R"(
[scene]
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [0.1, 0.03, 0.03], divisions = [6, 2, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = )" + std::to_string(nu) +
                                  R"(
density = 1000.0
retardation_time = )" + std::to_string(tau) +
                                  R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.01, -0.01, 0.005]
[solver]
springs = ")" + springs + R"("
)",
                              "box.toml", ".");
  return build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
}

TEST(Integrators3D, BothTensorFiltersRelineariseAndReportIt) {
  // summary.json's tensor_relinearizations and tensor_fallback_steps are each tensor filter's
  // counts (the factor's and the V-cycle's). The clamped box's end load at 300x bends it past
  // the trusted distortion within the run: both filters linearise again and keep every step.
  Model<3> model = clamped_box(0.05);
  model.loads.front().force *= 300.0;
  model.duration = 0.3;
  model.output_interval = 0.3;
  for (const std::string filter : {"tensor", "tensor-multigrid"}) {
    Trajectory<3> tr;
    const RunReport r = simulate(model, opts("filtered", 0.01, filter, false), tr, false);
    ASSERT_TRUE(r.stable) << filter;
    const auto extra = [&](const std::string& key) {
      const auto it = std::find_if(r.extra.begin(), r.extra.end(), [&](const auto& e) { return e.first == key; });
      return it == r.extra.end() ? -1.0 : it->second;
    };
    EXPECT_GT(extra("tensor_relinearizations"), 0) << filter;
    EXPECT_EQ(extra("tensor_fallback_steps"), 0) << filter;
  }
}

TEST(Integrators3D, FullFilterIsStableAtAHundredTimesTheExplicitStep) {
  // The 2D test's claim in 3D: the full filter is linearised backward Euler with a scalar
  // Laplacian, unconditionally stable for the linear problem. Undamped clamped box under a
  // step load at 100x the Courant step: bounded, and at the same static state as implicit
  // Euler (both fixed points of F_int + F_ext = 0) to 1e-6 once the transient has decayed.
  Model<3> model = clamped_box(0.0);
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  const double dt = 100 * dtc;
  model.duration = 4000 * dt;
  model.output_interval = model.duration;
  Trajectory<3> a, b;
  ASSERT_TRUE(simulate(model, opts("filtered", dt), a, true).stable);
  ASSERT_TRUE(simulate(model, opts("implicit-euler", dt), b, true).stable);
  EXPECT_LT((a.field.back() - b.field.back()).norm(), 1e-6 * b.field.back().norm());
  // The tensor filter is backward Euler with the rest Jacobian: stable there too.
  Trajectory<3> c;
  ASSERT_TRUE(simulate(model, opts("filtered", dt, "tensor"), c, true).stable);
  EXPECT_LT((c.field.back() - b.field.back()).norm(), 1e-6 * b.field.back().norm());
}

TEST(Integrators, TensorFilterStaysStableWhereShearTurnsSpringsApart) {
  // The paper's 517-node plate under its step pull (tau = 2 s, strains to 0.13) at dt = 10 ms,
  // 2.6e5 explicit steps, and at a third of its stiffness: shear turns springs away from their
  // nodes' rotations, and the dashpot force along that difference, which the frozen Jacobian
  // leaves explicit, diverged at t = 3.9 s before the transverse cover. Stable now, and at the
  // same rest state as implicit Euler (both fixed points of f_int + f_ext = 0, the transient
  // decayed to 1e-3 of the displacement after 5 tau: exp(-5) times the first-order lag).
  for (const double scale : {1.0, 0.3}) {
    Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/plate517_step.toml");
    scene.material.young_modulus *= scale;
    scene.duration = 10.0;
    const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
    Trajectory<2> tensor, ie;
    ASSERT_TRUE(simulate(model, opts("filtered", 0.01, "tensor", false), tensor, true).stable) << "scale " << scale;
    ASSERT_TRUE(simulate(model, opts("implicit-euler", 0.01), ie, true).stable);
    EXPECT_LT((tensor.field.back() - ie.field.back()).norm(), 1e-2 * ie.field.back().norm()) << "scale " << scale;
  }
}

/// A user's pull stepped as the viewer steps it: a spring of 4x the mean spring stiffness from
/// `node` toward `target`, its force in State::applied and, when `implicit`, its stiffness in
/// State::applied_stiffness. Returns the largest spring strain over the run (infinity once the
/// state is not finite), the node's last position in `end` and, for the tensor filter, how many
/// steps it handed to the full filter in `fallback`.
double pulled_run(const Model<2>& model, const IntegratorOptions& o, int node, const Vec<2>& target, double T,
                  bool implicit, Vec<2>& end, long* fallback = nullptr) {
  auto integ = make_integrator(model, o);
  const auto* filtered = dynamic_cast<const FilteredImplicit<2>*>(integ.get());
  const auto count = [&] {
    if (fallback && filtered) *fallback = filtered->fallback_steps();
  };
  State<2> s = initial_state(model);
  const auto n = model.num_nodes();
  s.applied = Nodal<2>::Zero(2, n);
  s.applied_stiffness = Eigen::VectorXd::Zero(n);
  const double k = 4 * model.net.stiffness.mean();
  double worst = 0;
  for (long step = 0; step < std::lround(T / o.dt); ++step) {
    end = model.net.rest.col(node) + s.u.col(node);
    s.applied.col(node) = k * (target - end);
    if (implicit) s.applied_stiffness[node] = k;
    integ->step(s);
    count();
    if (!s.u.allFinite()) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, max_strain(model.net, s.u));
  }
  end = model.net.rest.col(node) + s.u.col(node);
  return worst;
}

TEST(Integrators, TensorFilterRelinearisesPastItsTrustedDistortion) {
  // The four-force plate at a tenth of its stiffness (strains to 0.89), dt = 10 ms: shear
  // turns the springs up to 0.65 away from their nodes' rotations, and with the rest shape as
  // its only reference the tensor filter diverged at t = 4.52 s (the cover at the whole
  // transverse stiffness); implicit Euler then took 100 of the 600 steps, 10x the filter's
  // step each. Past kTrustedMismatch the filter now linearises again at the current shape
  // (relinearize): the run holds with no step handed over, and the count is reported.
  Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/plate517_four_forces.toml");
  scene.material.young_modulus *= 0.1;
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  FilteredImplicit<2> tensor(model, opts("filtered", 0.01, "tensor", false));
  State<2> s = initial_state(model);
  const long steps = std::lround(scene.duration / 0.01);
  for (long k = 0; k < steps; ++k) {
    tensor.step(s);
    ASSERT_TRUE(s.u.allFinite()) << "t = " << s.t;
  }
  EXPECT_EQ(tensor.fallback_steps(), 0);
  EXPECT_GT(tensor.relinearizations(), 0);
  EXPECT_GE(tensor.refactorizations(), tensor.relinearizations());
  // A run reports the counts (summary.json's tensor_relinearizations, tensor_fallback_steps).
  Trajectory<2> reported;
  const RunReport r = simulate(model, opts("filtered", 0.01, "tensor", false), reported, false);
  const auto extra = [&](const std::string& key) {
    const auto it = std::find_if(r.extra.begin(), r.extra.end(), [&](const auto& e) { return e.first == key; });
    return it == r.extra.end() ? -1.0 : it->second;
  };
  EXPECT_EQ(extra("tensor_relinearizations"), static_cast<double>(tensor.relinearizations()));
  EXPECT_EQ(extra("tensor_fallback_steps"), 0.0);
  EXPECT_EQ(r.fallback_steps, 0);
  EXPECT_EQ(r.filter_most_steps, "tensor");
  const std::string summary = summary_json(r, "four-forces");
  EXPECT_NE(summary.find("\"filter_most_steps\": \"tensor\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"tensor_relinearizations\""), std::string::npos) << summary;
  // The end state against implicit Euler's: both are first-order in dt about the same
  // trajectory, and the loads are held from t = 1 s, so after the remaining retardation
  // times (tau = 2 s) both sit near the same static state; their difference is what is
  // left of the transient's first-order errors.
  Trajectory<2> ie;
  ASSERT_TRUE(simulate(model, opts("implicit-euler", 0.01), ie, true).stable);
  EXPECT_LT((s.u - ie.field.back()).norm(), 1e-2 * ie.field.back().norm());
}

TEST(Integrators, TensorFilterHoldsAStiffPullByTakingItsSpringIntoTheSolve) {
  // The paper's 517-node plate under its step load at dt = 10 ms, and the viewer's pull near
  // its free lower corner, 2 mm straight down. Applied explicitly, the pull's spring (4x a spring)
  // diverged within 0.3 s (runaway strain 2.1 in the viewer at 0.22 s): where the corner's own
  // springs are weak, the tensor filter's H holds little more than the node's mass. Since the
  // fallback (past the trusted distortion the full filter steps) it no longer diverges, but it
  // distorts the corner until the tensor filter gives up its steps. In the solve (Woodbury on
  // the factor) the tensor filter holds it by itself: no step handed over, the strain of a
  // 2 mm pull (the full filter's, which treats it explicitly but carries its extra mass, is the
  // yardstick: within 2x of it), and the corner settles within 1 mm of the target (a spring 4x
  // the plate's own pulls it most of the way). (Since each spring has its own cover the
  // explicit pull holds too on this plate, but nothing guarantees it: the implicit one is kept.)
  const Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/plate517_step.toml");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  const int corner = nearest_node(model.mesh, Vec<2>(0.2, 0.01)); // the viewer's --drag 0.2,0.01:0.2,0.008
  const Vec<2> target(0.2, 0.008);
  Vec<2> end;
  long fallback = 0;
  const double tensor =
      pulled_run(model, opts("filtered", 0.01, "tensor", false), corner, target, 3.0, true, end, &fallback);
  ASSERT_TRUE(std::isfinite(tensor));
  EXPECT_EQ(fallback, 0);
  EXPECT_LT((end - target).norm(), 1e-3) << end.transpose();
  const double full = pulled_run(model, opts("filtered", 0.01, "full", false), corner, target, 3.0, false, end);
  EXPECT_LT(tensor, 2 * full) << "tensor " << tensor << ", full " << full;
}

/// The field after `pulled_run`'s pull (the viewer's, its stiffness in the solve) for T seconds.
Nodal<2> pulled_field(const Model<2>& model, const IntegratorOptions& o, int node, const Vec<2>& target, double T) {
  auto integ = make_integrator(model, o);
  State<2> s = initial_state(model);
  const auto n = model.num_nodes();
  s.applied = Nodal<2>::Zero(2, n);
  s.applied_stiffness = Eigen::VectorXd::Zero(n);
  const double k = 4 * model.net.stiffness.mean();
  for (long step = 0; step < std::lround(T / o.dt); ++step) {
    s.applied.col(node) = k * (target - model.net.rest.col(node) - s.u.col(node));
    s.applied_stiffness[node] = k;
    integ->step(s);
  }
  return s.u;
}

TEST(Integrators, TensorFilterDoesNotFoldThePlateUnderAHardPull) {
  // The viewer's hard pulls on the paper's 517-node plate (docs/viewer.md): its middle top
  // node dragged 2.2 cm up and right, its free lower corner 2.8 cm out, at dt = 10 and 40 ms.
  // Implicit Euler keeps the plate nearly straight (strains to 0.6-0.8 by the grabbed node).
  // The tensor filter used to hand such steps to the full filter with the momentum of its
  // own lag-free steps, and the plate ended folded: its field 37-403 % of implicit Euler's
  // from it after 1.2 s. Past the trusted distortion the tensor filter now linearises again at
  // the current shape and keeps the steps: within 10 % of implicit Euler's run (measured 7.1 /
  // 1.0 % for the middle pull at dt 10 / 40 ms, 0.8 / 3.1 % for the corner; with implicit Euler
  // taking those steps it was 2.4-3.2 %, and the full filter alone, with its extra mass, is at
  // 3.4-35 %).
  const Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/plate517_step.toml");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  for (const auto& [from, to] :
       {std::pair{Vec<2>(0.1, 0.05), Vec<2>(0.11, 0.07)}, std::pair{Vec<2>(0.2, 0.01), Vec<2>(0.22, -0.01)}}) {
    const int node = nearest_node(model.mesh, from);
    for (const double dt : {0.01, 0.04}) {
      const Nodal<2> ie = pulled_field(model, opts("implicit-euler", dt), node, to, 1.2);
      const Nodal<2> tensor = pulled_field(model, opts("filtered", dt, "tensor", false), node, to, 1.2);
      EXPECT_LT((tensor - ie).norm(), 0.1 * ie.norm()) << "pull from " << from.transpose() << ", dt " << dt;
    }
  }
}

TEST(Integrators3D, NeighbourFilterIsStableAtTheExplicitStepAndDivergesAtTenTimes) {
  // The truncation's conditional stability in 3D (undamped clamped box): stable at the
  // explicit limit, divergent at 10x, as on the plate.
  Model<3> model = clamped_box(0.0);
  expect_neighbour_filter_stable_only_at_the_explicit_step(model, {1.0, 10.0});
}

TEST(Integrators3D, ImplicitEulerByConjugateGradientsIsTheDirectSolveToItsTolerance) {
  // The same linearised backward-Euler step, solved by warm-started block-Jacobi CG to
  // |r| <= 1e-10 |b| instead of by the LDL^T factor. Each step's dv then differs by at most
  // cond(A) 1e-10 relative (cond(A) < 1e3 here: M + dt tau K at dt = 1 ms), and the damped,
  // unconditionally stable scheme does not amplify those differences: the trajectories agree
  // to 1e-6 of the displacement, in 3D (where auto picks a CG) and in 2D, with either
  // preconditioner (block Jacobi, or the multigrid V-cycle of the isotropic part).
  Model<3> box = clamped_box(0.05);
  box.duration = 0.3;
  box.output_interval = 0.05;
  Model<2> plate = test::model_from(test::plate_scene(12, 4, "[[fix]]\ngroup = \"left\"\n"));
  plate.duration = 0.3;
  plate.output_interval = 0.05;
  auto check = [](const auto& model, const char* linear_solver) {
    using Traj = Trajectory<std::decay_t<decltype(model)>::dimension>;
    Traj direct, cg;
    IntegratorOptions a = opts("implicit-euler", 1e-3), b = a;
    a.linear_solver = "direct";
    b.linear_solver = linear_solver;
    b.cg_tolerance = 1e-10;
    ASSERT_TRUE(simulate(model, a, direct, true).stable);
    ASSERT_TRUE(simulate(model, b, cg, true).stable);
    ASSERT_EQ(direct.field.size(), cg.field.size());
    const double scale = direct.field.back().norm();
    ASSERT_GT(scale, 0.0);
    double worst = 0;
    for (std::size_t k = 0; k < cg.field.size(); ++k) worst = std::max(worst, (cg.field[k] - direct.field[k]).norm());
    std::cout << linear_solver << " against direct: " << worst / scale << " relative\n";
    EXPECT_LT(worst, 1e-6 * scale) << linear_solver;
  };
  // With the volume term per cell (nu = 0.45: most of lambda in it), whose blocks CG applies
  // cell by cell and the factor takes through its own slots.
  Model<3> vbox = clamped_box(0.05, "volume", 0.45);
  vbox.duration = 0.3;
  vbox.output_interval = 0.05;
  std::string vtext = test::plate_scene(12, 4, "[[fix]]\ngroup = \"left\"\n[solver]\nsprings = \"volume\"\n");
  vtext.replace(vtext.find("poisson_ratio = 0.3333"), 22, "poisson_ratio = 0.45");
  Model<2> vplate = test::model_from(vtext);
  vplate.duration = 0.3;
  vplate.output_interval = 0.05;
  ASSERT_GT(vbox.net.volume.stiffness.sum(), 0.0);
  ASSERT_GT(vplate.net.volume.stiffness.sum(), 0.0);
  for (const char* linear_solver : {"cg", "cg-multigrid"}) {
    check(box, linear_solver);
    check(plate, linear_solver);
    check(vbox, linear_solver);
    check(vplate, linear_solver);
  }
}

} // namespace
} // namespace vtb
