// The neo-Hookean reference (`kinematics = "neo-hookean"`) against closed-form large-strain
// answers: a unit cube whose every boundary node is driven along a homogeneous deformation
// x = F X. P1 elements hold a homogeneous field exactly, so the interior follows it and the
// reactions summed over a face are the law's first Piola-Kirchhoff traction P N times the face's
// area, to the Newton tolerance (1e-9 of the load): checked to 1e-6 relative. The same runs
// with the St. Venant-Kirchhoff law ("nonlinear") give its own closed form and miss the
// neo-Hookean one by 10 % to 60 % at these strains, so the checks tell the laws apart.
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/meshes/msh_io.hh"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

namespace vtb {
namespace {

constexpr double kE = 1000, kNu = 0.3;
const double kLambda = kE * kNu / ((1 + kNu) * (1 - 2 * kNu)), kMu = kE / (2 * (1 + kNu));

using Mat3 = Eigen::Matrix3d;

struct Case3 {
  Scene scene;
  Problem<3> problem;
};

Mat3 neo_hookean_P(const Mat3& F) {
  const Mat3 FinvT = F.inverse().transpose();
  return kMu * (F - FinvT) + kLambda * std::log(F.determinant()) * FinvT;
}

Mat3 svk_P(const Mat3& F) {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  return F * (kLambda * E.trace() * Mat3::Identity() + 2 * kMu * E);
}

double extra(const RunReport& r, const std::string& key) {
  for (const auto& [k, v] : r.extra)
    if (k == key) return v;
  ADD_FAILURE() << "no " << key;
  return std::nan("");
}

/// The sums of the reactions over the faces X = 1 and Y = 1 of the cube driven along F.
struct FaceForces {
  Eigen::Vector3d x1, y1;
};

FaceForces drive_cube(const Mat3& F, const std::string& kinematics) {
  const Scene scene = parse_scene(R"(
[scene]
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [1.0, 1.0, 1.0], divisions = [3, 3, 3] }
[material]
young_modulus = 1000.0
poisson_ratio = 0.3
density = 1.0
[[fix]]
box = [[-0.1, -0.1, -0.1], [0.1, 0.1, 0.1]]
[solver]
kind = "fem"
static = true
dt = 1.0
kinematics = ")" + kinematics + "\"\n",
                                  "cube.toml", std::filesystem::temp_directory_path());
  Problem<3> problem = build_problem<3>(scene, std::get<Mesh3>(load_mesh(scene)));
  // Every boundary node its own drive, to its place on x = F X.
  problem.supports.clear();
  const auto& X = problem.mesh.points;
  for (int i = 0; i < problem.num_nodes(); ++i) {
    const Eigen::Vector3d p = X.col(i);
    if ((p.array() > 1e-9).all() && (p.array() < 1 - 1e-9).all()) continue;
    Support<3> s;
    s.nodes = {i};
    s.driven = true;
    s.displacement = (F - Mat3::Identity()) * p;
    problem.supports.push_back(s);
  }
  Trajectory<3> tr;
  const RunReport r = fem::simulate<3>(problem, scene.material, fem::options_from(scene.solver), tr, true);
  EXPECT_TRUE(r.stable) << r.failure;
  // The smallest det F over the quadrature points of the accepted states: each state of the
  // continuation is homogeneous, F(s) = I + s (F - I), and det F(s) falls monotonically to the
  // end's in compression (the last state, to Newton's tolerance), stays 1 in an isochoric one,
  // and rises in expansion (the first increment's, above 1).
  const double J = F.determinant(), smallest = extra(r, "min_volume_ratio");
  if (J < 1 + 1e-12)
    EXPECT_NEAR(smallest, J, 1e-9);
  else
    EXPECT_TRUE(smallest > 1 && smallest < J) << smallest;
  FaceForces f{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (std::size_t s = 0; s < problem.supports.size(); ++s) {
    const Eigen::Vector3d p = X.col(problem.supports[s].nodes[0]);
    if (p.x() > 1 - 1e-9) f.x1 += tr.reaction.back()[s];
    if (p.y() > 1 - 1e-9) f.y1 += tr.reaction.back()[s];
  }
  // The interior nodes follow the homogeneous field.
  for (int i = 0; i < problem.num_nodes(); ++i)
    EXPECT_LT((tr.field.back().col(i) - (F - Mat3::Identity()) * X.col(i)).norm(), 1e-9) << "node " << i;
  return f;
}

/// The lateral stretch of uniaxial stress at axial stretch l: P22 = 0, i.e.
/// mu (t^2 - 1) + lambda ln(l t^2) = 0 (Newton on t, monotone in t).
double uniaxial_lateral_stretch(double l) {
  double t = 1;
  for (int it = 0; it < 50; ++it)
    t -= (kMu * (t * t - 1) + kLambda * std::log(l * t * t)) / (2 * kMu * t + 2 * kLambda / t);
  return t;
}

TEST(NeoHookeanFem, UniaxialStressOfABlockToHalfAndOneAndAHalf) {
  for (const double l : {0.5, 1.5}) {
    const double t = uniaxial_lateral_stretch(l);
    const Mat3 F = Eigen::Vector3d(l, t, t).asDiagonal();
    const Mat3 P = neo_hookean_P(F);
    ASSERT_LT(std::abs(P(1, 1)), 1e-12 * std::abs(P(0, 0))); // the closed form is uniaxial
    const FaceForces nh = drive_cube(F, "neo-hookean");
    EXPECT_NEAR(nh.x1.x(), P(0, 0), 1e-6 * std::abs(P(0, 0))) << "stretch " << l;
    EXPECT_LT(nh.y1.norm(), 1e-6 * std::abs(P(0, 0))) << "stretch " << l << ": the lateral faces carry no load";
    const FaceForces svk = drive_cube(F, "nonlinear");
    EXPECT_NEAR(svk.x1.x(), svk_P(F)(0, 0), 1e-6 * std::abs(svk_P(F)(0, 0))) << "stretch " << l;
    EXPECT_GT(std::abs(svk.x1.x() - P(0, 0)), 0.1 * std::abs(P(0, 0))) << "the SVK law would pass at " << l;
  }
}

TEST(NeoHookeanFem, SimpleShearHasTheLinearShearStressAndNoNormalTraction) {
  // F = I + gamma e1 e2^T: J = 1 and P = mu (F - F^-T), so the face Y = 1 carries (mu gamma, 0, 0)
  // and X = 1 carries (0, mu gamma, 0). SVK's P N on Y = 1 has the normal part (lambda/2 + mu) gamma^2.
  const double gamma = 0.5;
  Mat3 F = Mat3::Identity();
  F(0, 1) = gamma;
  const FaceForces nh = drive_cube(F, "neo-hookean");
  const double tol = 1e-6 * kMu * gamma;
  EXPECT_NEAR(nh.y1.x(), kMu * gamma, tol);
  EXPECT_NEAR(nh.y1.y(), 0.0, tol);
  EXPECT_NEAR(nh.x1.y(), kMu * gamma, tol);
  EXPECT_NEAR(nh.x1.x(), 0.0, tol);
  const FaceForces svk = drive_cube(F, "nonlinear");
  EXPECT_NEAR(svk.y1.y(), svk_P(F)(1, 1), 1e-6 * std::abs(svk_P(F)(1, 1)));
  EXPECT_GT(std::abs(svk.y1.y()), 0.1 * kMu * gamma) << "the SVK law would pass";
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

/// A block 20 x 20 x 10 mm clamped underneath, a 0.3 N load on a patch of its top ramped over
/// the run (E 5 kPa, nu 0.45: the patch sinks more than 20 % of the thickness).
Case3 press(const std::string& solver) {
  Case3 c;
  c.scene = parse_scene(R"(
[scene]
duration = 1.0
output_interval = 0.25
[mesh]
generate = { shape = "box", size = [0.02, 0.02, 0.01], divisions = [4, 4, 2] }
[material]
young_modulus = 5.0e3
poisson_ratio = 0.45
density = 1000.0
[[fix]]
group = "front"
[[load]]
box = [[0.005, 0.005, 0.01], [0.015, 0.015, 0.01]]
total_force = [0.0, 0.0, -0.3]
ramp = 1.0
[[probe]]
name = "centre"
point = [0.01, 0.01, 0.01]
[solver]
kind = "fem"
static = true
kinematics = "neo-hookean"
)" + solver,
                        "press.toml", std::filesystem::temp_directory_path());
  c.problem = build_problem<3>(c.scene, std::get<Mesh3>(load_mesh(c.scene)));
  return c;
}

/// The press under `solver` with a FemOptions switch on and off: both reports and the probe's
/// last displacement in each.
struct OnAndOff {
  RunReport on, off;
  Eigen::Vector3d u_on, u_off;
};
OnAndOff on_and_off(const std::string& solver, bool fem::FemOptions::*option) {
  const Case3 c = press(solver);
  fem::FemOptions on = fem::options_from(c.scene.solver), off = on;
  on.*option = true;
  off.*option = false;
  Trajectory<3> a, b;
  OnAndOff r{fem::simulate<3>(c.problem, c.scene.material, on, a),
             fem::simulate<3>(c.problem, c.scene.material, off, b),
             {},
             {}};
  if (r.on.stable && r.off.stable) r.u_on = a.probe_u.back()[0], r.u_off = b.probe_u.back()[0];
  return r;
}

TEST(NeoHookeanFem, TheSecantPredictorChangesNewtonsWorkNotTheAnswer) {
  // The static continuation starts each increment from the last two equilibria extrapolated to
  // its load factor. The equilibrium does not depend on the guess: both runs end at Newton's
  // tolerance (1e-9 of the load), so the answers agree to 1e-7 of the displacement, while the
  // predictor's start is nearer the path and Newton needs fewer iterations.
  const auto [ra, rb, ua, ub] = on_and_off("", &fem::FemOptions::secant_predictor);
  ASSERT_TRUE(ra.stable && rb.stable);
  EXPECT_LT((ua - ub).norm(), 1e-7 * ub.norm());
  std::cout << "Newton iterations with the predictor " << extra(ra, "newton_iterations") << ", without "
            << extra(rb, "newton_iterations") << "; increments " << extra(ra, "load_increments") << " and "
            << extra(rb, "load_increments") << "\n";
  EXPECT_LT(extra(ra, "newton_iterations"), extra(rb, "newton_iterations"));
  // A press this deep squeezes the cells under the patch, none through (J > 0 is neo-Hookean's).
  EXPECT_GT(extra(ra, "min_volume_ratio"), 0.0);
  EXPECT_LT(extra(ra, "min_volume_ratio"), 0.99);
}

TEST(NeoHookeanFem, AStaticPathPassesThroughEachLoadsEquilibrium) {
  // `static_path` solves the equilibrium at every sample (0.25, 0.5, 0.75, 1 of the load here),
  // each continued from the last; the equilibrium of a load does not depend on the path to it,
  // so each sample is the one static solve of its load (the run's duration set to the sample's
  // time), to the Newton tolerance (1e-9 of the load): 1e-7 of the displacement.
  const Case3 path = press("static_path = true\n");
  Trajectory<3> tr;
  ASSERT_TRUE(fem::simulate<3>(path.problem, path.scene.material, fem::options_from(path.scene.solver), tr).stable);
  ASSERT_EQ(tr.t.size(), 5u);
  std::cout << "path end: " << tr.probe_u.back()[0].z() << " m\n";
  EXPECT_LT(tr.probe_u.back()[0].z(), -0.002) << "a deep press";
  for (std::size_t k = 1; k < tr.t.size(); ++k) {
    Case3 once = press("");
    once.problem.duration = tr.t[k];
    Trajectory<3> one;
    ASSERT_TRUE(fem::simulate<3>(once.problem, once.scene.material, fem::options_from(once.scene.solver), one).stable);
    EXPECT_LT((tr.probe_u[k][0] - one.probe_u.back()[0]).norm(), 1e-7 * one.probe_u.back()[0].norm()) << tr.t[k];
  }
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(NeoHookeanFem, NestedIterationStartsTheRefinedLevelFromTheCoarseAnswer) {
  // P2 refined once, static: the solve first runs on the mesh (P2) and starts Newton at the whole
  // load from that answer instead of continuing from rest. The equilibrium does not depend on
  // the start: both end at Newton's tolerance (1e-9 of the load), so the answers agree to 1e-7 of
  // the displacement, while the coarse answer (within the discretisation error of the fine one)
  // saves the fine level its continuation's increments. The reported move is the probe's change
  // between the levels, which the P2 run on the mesh gives independently.
  const Case3 c = press("degree = 2\nrefinements = 1\n");
  fem::FemOptions nested = fem::options_from(c.scene.solver), from_rest = nested, coarse = nested;
  from_rest.nested = false;
  coarse.refinements = 0;
  Trajectory<3> a, b, k;
  const RunReport ra = fem::simulate<3>(c.problem, c.scene.material, nested, a);
  const RunReport rb = fem::simulate<3>(c.problem, c.scene.material, from_rest, b);
  const RunReport rk = fem::simulate<3>(c.problem, c.scene.material, coarse, k);
  ASSERT_TRUE(ra.stable && rb.stable && rk.stable);
  const Eigen::Vector3d ua = a.probe_u.back()[0], ub = b.probe_u.back()[0], uk = k.probe_u.back()[0];
  EXPECT_LT((ua - ub).norm(), 1e-7 * ub.norm());
  EXPECT_EQ(extra(ra, "nested_start_converged"), 1.0);
  EXPECT_EQ(extra(ra, "load_increments"), 1.0);
  std::cout << "fine-level Newton iterations nested " << extra(ra, "newton_iterations") << " (+ "
            << extra(ra, "nested_coarse_newton_iterations") << " on the mesh), from rest "
            << extra(rb, "newton_iterations") << "; the probe moved " << extra(ra, "nested_probe_move") << "\n";
  EXPECT_LT(extra(ra, "newton_iterations"), extra(rb, "newton_iterations"));
  EXPECT_EQ(extra(ra, "nested_coarse_dofs"), extra(rk, "dofs"));
  EXPECT_EQ(extra(ra, "nested_coarse_newton_iterations"), extra(rk, "newton_iterations"));
  // The move: |u_fine - u_coarse| / |u_fine| at the probe, to the Newton tolerance of both runs.
  EXPECT_NEAR(extra(ra, "nested_probe_move"), (ua - uk).norm() / ua.norm(), 1e-6);
  EXPECT_GT(extra(ra, "nested_probe_move"), 0.0); // refinement moves a P2 press's answer
}

TEST(NeoHookeanFem, TheLineSearchIsWhatLetsTheNestedStartConverge) {
  // The coarse answer carried over exactly leaves a residual where the finer level resolves
  // more of the disc's rim; Newton's whole first correction from it overshoots (the potential
  // rises along it) and the start wanders off. The line search shortens that correction and the
  // start converges; without it the solve falls back to the continuation from rest and ends at
  // the same equilibrium (Newton's tolerance, 1e-9 of the load: 1e-7 of the displacement).
  const auto [ra, rb, ua, ub] = on_and_off("degree = 2\nrefinements = 1\n", &fem::FemOptions::line_search);
  ASSERT_TRUE(ra.stable && rb.stable);
  EXPECT_EQ(extra(ra, "nested_start_converged"), 1.0);
  EXPECT_GE(extra(ra, "newton_line_searches"), 1.0);
  EXPECT_EQ(extra(rb, "nested_start_converged"), 0.0);
  EXPECT_EQ(extra(rb, "newton_line_searches"), 0.0);
  EXPECT_LT((ua - ub).norm(), 1e-7 * ub.norm());
}

} // namespace
} // namespace vtb
