// CVODE as the reference of the discrete spring model.
#include "support/small_models.hh"
#include "vtb/solvers/cvode_solver.hh"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include <cmath>
#include <iostream>
#include <limits>

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

TEST(Cvode, HonoursAppliedForcesAsTheOtherIntegratorsDo) {
  // The single element with no load but an applied force F on its free node (as a haptic
  // device would push it) creeps exactly as the loaded element does: x = F/k (1 - exp(-t/tau)),
  // to CVODE's tolerance (the same bound as the loaded case above). Without the applied force
  // the node stays at rest, so a CVODE that ignored it fails by the whole 0.02.
  Model<2> model = test::single_element(100.0, 10.0, 1e-6, 0.0);
  model.duration = 0.5;
  model.output_interval = 0.05;
  Eigen::MatrixXd applied = Eigen::MatrixXd::Zero(2, 2);
  applied(0, 1) = 2.0;
  Trajectory<2> tr;
  const RunReport r = simulate_cvode(model, CvodeOptions{1e-9, 1e-14}, tr, true, applied);
  ASSERT_TRUE(r.stable) << r.failure;
  for (std::size_t k = 0; k < tr.t.size(); ++k)
    EXPECT_NEAR(tr.field[k](0, 1), 0.02 * (1 - std::exp(-10.0 * tr.t[k])), 1e-6 * 0.02) << "t = " << tr.t[k];
  // The right-hand side itself: the applied force enters v' as F / m.
  const Eigen::VectorXd y = Eigen::VectorXd::Zero(4);
  EXPECT_NEAR(cvode_rhs<2>(model, 0.0, y, applied)(2) - cvode_rhs<2>(model, 0.0, y)(2), 2.0 / 1e-6, 1e-6);
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

/// A 3D box with a ramped traction, a ramped drive (prescribed u and v inside the right-hand
/// side), mass damping and a clamp.
Model<3> ramped_driven_box() {
  const Scene s = parse_scene(R"(
[scene]
duration = 0.2
output_interval = 0.02
[mesh]
generate = { shape = "box", size = [0.1, 0.03, 0.03], divisions = [4, 2, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.25
density = 1000.0
retardation_time = 0.02
mass_damping = 2.0
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.0, -0.01, 0.005]
start = 0.02
ramp = 0.05
[[drive]]
point = [0.05, 0.03, 0.03]
displacement = [0.0, 0.002, 0.0]
start = 0.0
ramp = 0.1
)",
                              "box.toml", ".");
  return build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
}

TEST(Cvode, ImplicitEulerConvergesToCvodeAtFirstOrderIn3DWithRampsAndDrives) {
  // The 3D path of CVODE, with a ramped traction and a ramped drive (prescribed u and v inside
  // the right-hand side), mass damping and a clamp. Implicit Euler's error against it halves
  // with dt (order 1: ratio 2 (1 + O(dt / T)), T = 0.01 s the shortest resolved period here,
  // so 2 within 0.2), and the drive's node sits at its prescribed displacement in both.
  const Model<3> model = ramped_driven_box();
  Trajectory<3> ref;
  ASSERT_TRUE(simulate_cvode(model, CvodeOptions{1e-10, 1e-15}, ref, true).stable);
  const int driven = model.supports.back().nodes.at(0);
  EXPECT_NEAR(ref.field.back()(1, driven), 0.002, 1e-15);
  auto error = [&](double dt) {
    IntegratorOptions o;
    o.kind = "implicit-euler";
    o.dt = dt;
    Trajectory<3> tr;
    EXPECT_TRUE(simulate(model, o, tr, true).stable);
    EXPECT_NEAR(tr.field.back()(1, driven), 0.002, 1e-15);
    double e = 0, scale = 0;
    for (std::size_t k = 0; k < ref.t.size(); ++k) {
      e = std::max(e, (tr.field[k] - ref.field[k]).norm());
      scale = std::max(scale, ref.field[k].norm());
    }
    return e / scale;
  };
  const double e2 = error(5e-4), e3 = error(2.5e-4);
  EXPECT_NEAR(e2 / e3, 2.0, 0.2) << e2 << " " << e3;
  EXPECT_LT(e3, 0.05) << "and small in absolute terms";
}

TEST(Cvode, GmresOnTheReducedNewtonSystemFollowsKluIn3D) {
  // In 3D CVODE's Newton systems go by default to GMRES, preconditioned by their exact inverse
  // for the clamped Jacobian (the reduced M + gamma D + gamma^2 K by CHOLMOD), not to KLU's LU
  // of the 2n x 2n block system. Both are CVODE at rtol 1e-9: each trajectory is within a small
  // multiple of rtol of the exact one (the global error of a tolerance-controlled BDF run, here
  // measured below 1e-7 relative), so they must agree to 1e-6 of the largest displacement, and
  // the drive holds its prescribed value in both. The preconditioner is exact up to the clamp
  // and the dashpots' omitted position terms, so GMRES needs about one iteration per Newton
  // iteration (at most 2 on average), and a factor is kept over many steps (CVODE's jok).
  const Model<3> model = ramped_driven_box();
  Trajectory<3> klu, gmres;
  CvodeOptions o{1e-9, 1e-14};
  o.linear_solver = "klu";
  const RunReport rk = simulate_cvode(model, o, klu, true);
  o.linear_solver = "auto";
  const RunReport rg = simulate_cvode(model, o, gmres, true);
  ASSERT_TRUE(rk.stable && rg.stable);
  const auto extra = [](const RunReport& r, const std::string& key) {
    for (const auto& [k, v] : r.extra)
      if (k == key) return v;
    return std::nan("");
  };
  EXPECT_TRUE(std::isnan(extra(rk, "preconditioner_factors"))) << "klu has no preconditioner";
  const double factors = extra(rg, "preconditioner_factors"), newton = extra(rg, "newton_iterations");
  ASSERT_GT(factors, 0) << "auto is gmres in 3D";
  EXPECT_LT(factors, extra(rg, "cvode_steps"));
  EXPECT_LE(extra(rg, "linear_iterations"), 2 * newton);
  double diff = 0, scale = 0;
  ASSERT_EQ(klu.t.size(), gmres.t.size());
  for (std::size_t k = 0; k < klu.t.size(); ++k) {
    diff = std::max(diff, (gmres.field[k] - klu.field[k]).norm());
    scale = std::max(scale, klu.field[k].norm());
  }
  EXPECT_LT(diff / scale, 1e-6);
  const int driven = model.supports.back().nodes.at(0);
  EXPECT_NEAR(gmres.field.back()(1, driven), 0.002, 1e-15);
  o.linear_solver = "lu";
  EXPECT_THROW(simulate_cvode(model, o, gmres), std::invalid_argument);
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

TEST(Cvode, TensorFilterTracksACantileverStepAsWellAsImplicitEuler) {
  // A cantilever strip (0.2 x 0.02, 20 x 2 cells) under a step load across its axis, against
  // CVODE at rtol 1e-10 (the exact discrete-model trajectory to ~1e-9): the tip history's
  // error relative to its peak. The full (scalar) filter is backward Euler with extra mass
  // dt (tau + dt)(K_L (x) I - K) and lags far behind; the tensor filter is backward Euler with
  // the Jacobian frozen at rest (exact for this small deflection up to O(rotation)), so its
  // error is implicit Euler's first-order one. Goal (the fidelity issue): at most 1.5x
  // implicit Euler's at dt = 1, 10 and 40 ms. Measured (with the per-spring transverse cover of
  // tensor_filter.hh and the step's correction toward implicit Euler's, which the cover's small
  // gain here mostly skips): 0.31/0.42, 2.88/3.91, 9.57/13.6 %; the full filter 15, 59, 92 %.
  // The reproduction's transient.csv runs the same scene.
  const Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/cantilever_step.toml");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  Trajectory<2> ref;
  ASSERT_TRUE(simulate_cvode(model, CvodeOptions{1e-10, 1e-15}, ref, true).stable);
  auto tip_error = [&](const std::string& kind, const std::string& filter, double dt) {
    IntegratorOptions o;
    o.kind = kind;
    o.filter = filter;
    o.dt = dt;
    Trajectory<2> tr;
    EXPECT_TRUE(simulate(model, o, tr, true).stable);
    double e = 0, peak = 0;
    for (std::size_t k = 0; k < ref.t.size(); ++k) {
      e = std::max(e, (tr.probe_u[k][0] - ref.probe_u[k][0]).norm());
      peak = std::max(peak, ref.probe_u[k][0].norm());
    }
    return e / peak;
  };
  for (const double dt : {1e-3, 1e-2, 4e-2}) {
    const double tensor = tip_error("filtered", "tensor", dt), ie = tip_error("implicit-euler", "", dt);
    const double full = tip_error("filtered", "full", dt);
    std::cout << "dt " << dt << ": tensor " << tensor << ", implicit Euler " << ie << ", full filter " << full << "\n";
    EXPECT_LE(tensor, 1.5 * ie) << "dt = " << dt;
    EXPECT_GT(full, 3 * tensor) << "the scalar filter's lag, which the tensor filter removes";
  }
}

/// The largest displacement error over a run's samples, relative to the reference's largest
/// displacement (compare.csv's displacement_error_max).
template <int dim> double field_error(const Trajectory<dim>& tr, const Trajectory<dim>& ref) {
  double e = 0, peak = 0;
  for (std::size_t k = 0; k < ref.field.size() && k < tr.field.size(); ++k) {
    e = std::max(e, (tr.field[k] - ref.field[k]).colwise().norm().maxCoeff());
    peak = std::max(peak, ref.field[k].colwise().norm().maxCoeff());
  }
  return tr.field.size() == ref.field.size() ? e / peak : std::numeric_limits<double>::infinity();
}

template <int dim>
void expect_tensor_filter_within_implicit_eulers_error(const char* scene_file, double duration,
                                                       std::initializer_list<const char*> filters = {"tensor"},
                                                       std::initializer_list<double> steps = {1e-3, 1e-2}) {
  Scene scene = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes" / scene_file);
  scene.duration = duration;
  const Model<dim> model = build_model<dim>(scene, std::get<Mesh<dim>>(load_mesh(scene)));
  Trajectory<dim> ref;
  ASSERT_TRUE(simulate_cvode(model, CvodeOptions{1e-8, 1e-14}, ref, true).stable);
  for (const double dt : steps) {
    IntegratorOptions o;
    o.dt = dt;
    o.kind = "implicit-euler";
    Trajectory<dim> ie;
    ASSERT_TRUE(simulate(model, o, ie, true).stable);
    const double e_ie = field_error(ie, ref);
    for (const char* filter : filters) {
      o.kind = "filtered";
      o.filter = filter;
      Trajectory<dim> tensor;
      ASSERT_TRUE(simulate(model, o, tensor, true).stable);
      const double e_tensor = field_error(tensor, ref);
      std::cout << scene_file << " dt " << dt << ": " << filter << " " << e_tensor << ", implicit Euler " << e_ie
                << "\n";
      EXPECT_LE(e_tensor, 1.5 * e_ie) << scene_file << " " << filter << " dt = " << dt;
    }
  }
}

TEST(Cvode, TensorFilterTracksASlabPressAndThePapersPlateAsWellAsImplicitEuler) {
  // Off the cantilever: the 3D slab pressed by a driven point (over its 0.5 s ramp and after)
  // and the paper's 517-node plate under its step pull, against CVODE (rtol 1e-8, far below
  // both fixed-step errors, which are first order: 0.05 % and 0.4 % at dt = 1 and 10 ms on the
  // slab). Goal: at most 1.5x implicit Euler's error. With one transverse cover for
  // the whole mesh (the largest mismatch's, set by the driven point's neighbourhood) the slab
  // was at 4.0x (the plate 1.6-1.7x): the cover's transverse damping slowed every spring's
  // rotation. With each spring's own cover (tensor_filter.hh) measured 1.1x and 1.02x.
  // The block V-cycle in place of H_t's factor (tensor-multigrid, the large-mesh form) adds the
  // extra mass Delta_t (B^-1 = H_t + Delta_t): measured 1.39x / 1.42x implicit Euler's error at
  // 1 / 10 ms before the step's correction, 1.43x / 1.43x while the correction rested after
  // small gains as a cover's does, 1.12x / 1.25x (over 2 s) now that it corrects every step
  // under the V-cycle; the factor's 1.14x / 1.12x.
  expect_tensor_filter_within_implicit_eulers_error<3>("slab_press.toml", 0.8, {"tensor", "tensor-multigrid"});
  expect_tensor_filter_within_implicit_eulers_error<2>("plate517_step.toml", 1.0);
}

/// summary.json's extra `key` of a run (-1 when absent).
double extra(const RunReport& r, const std::string& key) {
  const auto it = std::find_if(r.extra.begin(), r.extra.end(), [&](const auto& e) { return e.first == key; });
  return it == r.extra.end() ? -1.0 : it->second;
}

/// The tensor filters on a case past the rest Jacobian's trusted distortion: every
/// step the filter's (no implicit Euler fallback), every refactorisation spread over
/// kRefreshParts steps (none carried whole by one step), and the error against CVODE (rtol 1e-8,
/// far below the fixed-step errors) within 1.5x implicit Euler's (docs/performance.md's goal).
template <int dim>
void expect_bounded_tensor_steps(const std::string& text, std::initializer_list<const char*> filters,
                                 bool relinearizes) {
  const Scene scene = parse_scene(text, "large.toml", ".");
  const Model<dim> model = build_model<dim>(scene, std::get<Mesh<dim>>(load_mesh(scene)));
  Trajectory<dim> ref, ie;
  ASSERT_TRUE(simulate_cvode(model, CvodeOptions{1e-8, 1e-14}, ref, true).stable);
  IntegratorOptions o;
  o.dt = 1e-3;
  o.kind = "implicit-euler";
  ASSERT_TRUE(simulate(model, o, ie, true).stable);
  const double e_ie = field_error(ie, ref);
  for (const char* filter : filters) {
    o.kind = "filtered";
    o.filter = filter;
    Trajectory<dim> tr;
    const RunReport r = simulate(model, o, tr, true);
    ASSERT_TRUE(r.stable) << filter;
    const double e = field_error(tr, ref);
    std::cout << filter << ": error " << e << " (implicit Euler " << e_ie << "), max spring strain "
              << r.max_spring_strain << ", relinearisations " << extra(r, "tensor_relinearizations")
              << ", refactorisations " << extra(r, "tensor_refactorizations") << "\n";
    EXPECT_EQ(r.fallback_steps, 0) << filter;
    EXPECT_EQ(extra(r, "tensor_refreshes_at_once"), 0) << filter;
    EXPECT_GT(extra(r, "tensor_refactorizations"), 0) << filter << ": the case moves the filter's H";
    if (relinearizes) {
      EXPECT_GT(extra(r, "tensor_relinearizations"), 0) << filter;
    }
    EXPECT_LE(e, 1.5 * e_ie) << filter;
  }
}

TEST(Cvode, TensorFilterHoldsALargeStrainPullWithoutImplicitEuler) {
  // A 24 x 6 strip clamped on the left, 1 N on its right edge (EA = 2.5 N: springs stretched
  // past 0.4), tau 50 ms, dt 1 ms: the rest Jacobian's distortion passes kTrustedMismatch
  // within the first tens of steps. Before relinearize() implicit Euler took nearly every step
  // (the issue's 517-node pull: 1,979 of 2,000) at 10-20x the filter's cost.
  expect_bounded_tensor_steps<2>(test::pulled_plate(24, 6, "", "1.0, 0.0"), {"tensor"}, true);
}

TEST(Cvode, TensorFiltersPressANearlyIncompressibleBlockInBoundedSteps) {
  // A 4 x 3 x 4 cm block (6 x 5 x 6 cells), nu 0.49, E 5 kPa, tau 50 ms, bottom clamped and
  // pressed by 0.05 N on a 6 mm disc, dt 1 ms: the transverse cover moves as the press goes
  // in, each move a refactorisation (or a V-cycle refresh), which one step used to carry whole
  // (the issue's 2,448-node press: p99 14x the median step).
  const std::string text = R"(
[scene]
duration = 0.3
output_interval = 0.01
[mesh]
generate = { shape = "box", size = [0.04, 0.03, 0.04], divisions = [6, 5, 6] }
[material]
young_modulus = 5.0e3
poisson_ratio = 0.49
density = 1000.0
retardation_time = 0.05
[[fix]]
group = "bottom"
[[load]]
disc = { center = [0.02, 0.03, 0.02], radius = 0.01 }
total_force = [0.0, -0.3, 0.0]
[solver]
springs = "lloyd"
)";
  expect_bounded_tensor_steps<3>(text, {"tensor", "tensor-multigrid"}, false);
}

TEST(Cvode, TensorFiltersTrackATwistedBarAsWellAsImplicitEuler) {
  // Torsion in 3D: a square bar clamped at one end and twisted at the other
  // by a couple applied as a step, over its transient (tau = 20 ms, 0.6 s), against CVODE at
  // dt = 1, 10 and 40 ms. Twisting turns each cross-section, so the warped rest Jacobian is
  // what the filter relies on here. Measured here (CVODE at rtol 1e-8; largest relative
  // displacement error over the run): tensor 0.94x / 0.98x / 1.00x implicit Euler's, the block
  // V-cycle (tensor-multigrid) 0.99x / 1.00x / 0.99x: its extra mass Delta_t had made it 1.04x /
  // 1.38x / 1.46x before the step's correction toward implicit Euler's (TensorFilter::correct);
  // the full filter, with vtb compare's CVODE, 80 / 97 / 99 % (its lag), against 1.5 / 12 / 33 %.
  expect_tensor_filter_within_implicit_eulers_error<3>("bar_torsion.toml", 0.6, {"tensor", "tensor-multigrid"},
                                                       {1e-3, 1e-2, 4e-2});
}

TEST(Cvode, TensorFilterTracksThePapersPlateUnderFourForcesAsWellAsImplicitEuler) {
  // The paper's second case: the 517-node plate under a pull and three patch forces that start
  // as steps at t = 1, 2 and 3 s (the last ramped over 1 s), tau = 2 s, over its first 4.5 s,
  // at dt = 1, 10 and 40 ms. It is overdamped to the extreme (dt c / m ~ 1e5 at 10 ms), and
  // each load turns the springs by its patch, where the cover's transverse damping set the
  // filter 5.6x / 4.0x / 3.0x implicit Euler's error (over the scene's 10 s; the cover is what
  // keeps it stable at 10 and 40 ms). The step's correction toward implicit Euler's
  // (TensorFilter::correct) removes that lag: measured 0.35x / 0.39x / 0.47x over these 4.5 s
  // (0.26x / 0.47x / 0.57x over 10 s), and 6.2x / 4.5x / 3.3x without it.
  expect_tensor_filter_within_implicit_eulers_error<2>("plate517_four_forces.toml", 4.5, {"tensor"},
                                                       {1e-3, 1e-2, 4e-2});
}

} // namespace
} // namespace vtb
