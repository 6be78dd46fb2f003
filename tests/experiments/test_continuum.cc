// The continuum as the yardstick: the ladder of P2 refinements, the load check of a
// run against it, compare's continuum reference, and springs trained on it.
#include "vtb/fem/continuum.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/compare.hh"
#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/harness/study.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/springs/model.hh"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>

#include <iostream>

namespace vtb {
namespace {

/// A cantilever strip (L x H) on nx x ny union-jack cells, clamped on the left, a transverse
/// load on its right edge; `springs` names the constants.
Scene strip(int nx, int ny, const char* springs, double nu = 1.0 / 3.0) {
  return parse_scene("[scene]\nname = \"strip\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = "
                     "\"rectangle\", size = [0.2, 0.02], divisions = [" +
                         std::to_string(nx) + ", " + std::to_string(ny) +
                         "] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " + std::to_string(nu) +
                         "\ndensity = 1000.0\nthickness = 0.001\n[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = "
                         "\"right\"\ntotal_force = [0.0, -2.0e-4]\n[solver]\nsprings = \"" +
                         springs + "\"\n",
                     "strip.toml", ".");
}

/// The FEM's static answer at the scene's nodes with degree p and r refinements.
template <int dim> Nodal<dim> fem_static(const Problem<dim>& p, const MaterialDesc& m, int degree, int refinements) {
  fem::FemOptions o;
  o.degree = degree;
  o.refinements = refinements;
  o.static_solve = true;
  Trajectory<dim> out;
  fem::simulate<dim>(fem::static_problem(p), m, o, out, true);
  return out.field.back();
}

/// The springs' linear static answer (their stiffness at rest, held nodes at zero).
Nodal<2> springs_static(const Model<2>& model) {
  const Nodal<2> zero = Nodal<2>::Zero(2, model.num_nodes());
  const Eigen::SparseMatrix<double> K =
      free_dof_block<2>(Eigen::SparseMatrix<double>(-force_jacobians(model.net, zero, false).K), model);
  Nodal<2> f(2, model.num_nodes());
  model.external_forces(1e9, f);
  const auto nf = static_cast<Eigen::Index>(model.free_nodes.size());
  Eigen::VectorXd rhs(2 * nf);
  for (Eigen::Index a = 0; a < nf; ++a) rhs.segment<2>(2 * a) = f.col(model.free_nodes[static_cast<std::size_t>(a)]);
  const Eigen::VectorXd u = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(K).solve(rhs);
  Nodal<2> out = zero;
  for (Eigen::Index a = 0; a < nf; ++a) out.col(model.free_nodes[static_cast<std::size_t>(a)]) = u.segment<2>(2 * a);
  return out;
}

double relative(const Nodal<2>& u, const Nodal<2>& ref) {
  return (u - ref).norm() / ref.norm();
}

TEST(Continuum, TheLadderStopsWhereOneMoreRefinementMovesItLessThanItsTolerance) {
  const Scene scene = strip(20, 2, "lloyd");
  const Model<2> model = build_model<2>(scene, std::get<Mesh<2>>(load_mesh(scene)), {}, false);
  const auto ans = fem::continuum_static<2>(model, scene.material);
  ASSERT_TRUE(ans);
  EXPECT_TRUE(ans->converged) << ans->how;
  EXPECT_LT(ans->change, 0.01);
  EXPECT_EQ(ans->sufficient_refinements, ans->refinements - 1);
  // An independent check of the claim: one refinement beyond the ladder's finest level. P2's
  // nodal error falls by about 2^3 per halving of h on this smooth bending field, so the next
  // refinement moves the answer by less than the last one did (and so below the tolerance).
  const Nodal<2> finer = fem_static<2>(model, scene.material, 2, ans->refinements + 1);
  EXPECT_LT(relative(ans->u, finer), ans->change) << ans->how;
  EXPECT_NE(ans->how.find("converged"), std::string::npos);
}

TEST(Continuum, TheLadderSaysWhereItsBudgetStopsIt) {
  const Scene scene = strip(20, 2, "lloyd");
  const Model<2> model = build_model<2>(scene, std::get<Mesh<2>>(load_mesh(scene)), {}, false);
  fem::ContinuumOptions o;
  o.max_dofs = fem::continuum_first_dofs(model.mesh); // P2 on the mesh fits, one refinement more does not
  const auto ans = fem::continuum_static<2>(model, scene.material, o);
  ASSERT_TRUE(ans);
  EXPECT_FALSE(ans->converged);
  EXPECT_EQ(ans->refinements, 0);
  EXPECT_NE(ans->how.find("above the budget"), std::string::npos) << ans->how;
  o.max_dofs = fem::continuum_first_dofs(model.mesh) - 1; // not even P2 on the mesh
  EXPECT_FALSE(fem::continuum_static<2>(model, scene.material, o));
}

TEST(Continuum, ARunsLoadCheckIsAgainstTheContinuumAndP1OnATwoCellStripLocks) {
  // Lloyd's constants: no fit, so the check measures fixed springs.
  const Scene scene = strip(20, 2, "lloyd");
  const Yardstick yardstick = harness::continuum_yardstick();
  const Model<2> model = build_model<2>(scene, std::get<Mesh<2>>(load_mesh(scene)), {}, true, &yardstick);
  EXPECT_EQ(model.net.calibration_yardstick.rfind("the continuum (P2 refined", 0), 0u)
      << model.net.calibration_yardstick;
  // Measured independently: P2 refined twice (beyond the ladder's converged level, which moved
  // the answer by less than 1 %), so the run's numbers agree within a point (the bar).
  const Nodal<2> continuum = fem_static<2>(model, scene.material, 2, 2);
  const Nodal<2> p1 = fem_static<2>(model, scene.material, 1, 0);
  EXPECT_NEAR(model.net.calibration_load_error, relative(springs_static(model), continuum), 0.01);
  EXPECT_NEAR(model.net.mesh_fem_load_error, relative(p1, continuum), 0.01);
  // P1 on a strip two cells thick locks in bending: its constant-strain triangles cannot bend
  // without shearing, and the answer is stiff by a third or more (37 % here, 1.6x the springs'
  // own lattice error; docs/fidelity.md): a fit to P1 inherits it.
  EXPECT_GT(model.net.mesh_fem_load_error, 0.25);
  EXPECT_LT(p1.norm(), 0.8 * continuum.norm());
  // Without the continuum the check is P1's, and says so.
  const Model<2> p1_checked = build_model<2>(scene, std::get<Mesh<2>>(load_mesh(scene)));
  EXPECT_EQ(p1_checked.net.calibration_yardstick, "P1 FEM on the mesh");
  EXPECT_TRUE(std::isnan(p1_checked.net.mesh_fem_load_error));
}

TEST(Continuum, AReferenceTakesTheLoadChecksLadderWhereItIsTheSameSolve) {
  // The springs' load check solves the static ladder with the drives held; a study's reference
  // solves it with them displaced, compare's with them held. On a scene that drives nothing the
  // study's is the load check's solve, so it is kept rather than solved again: the same answer
  // to the bit. Another material or a driven support is another problem, solved afresh.
  const Scene scene = strip(20, 2, "lloyd");
  harness::KeptLadders kept;
  const Yardstick yardstick = harness::continuum_yardstick(&kept);
  const Model<2> model = build_model<2>(scene, std::get<Mesh<2>>(load_mesh(scene)), {}, true, &yardstick);
  ASSERT_TRUE(kept.plane) << "the load check solved the ladder";
  fem::ContinuumOptions displaced;
  displaced.drives_displaced = true;
  bool reused = false;
  const auto kept_answer = harness::static_ladder<2>(model, scene.material, displaced, &kept, &reused);
  EXPECT_TRUE(reused);
  const auto fresh = fem::continuum_static<2>(model, scene.material, displaced);
  ASSERT_TRUE(kept_answer && fresh);
  EXPECT_EQ((kept_answer->u - fresh->u).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(kept_answer->sufficient_refinements, fresh->sufficient_refinements);
  MaterialDesc stiffer = scene.material;
  stiffer.young_modulus *= 2;
  EXPECT_TRUE(harness::static_ladder<2>(model, stiffer, displaced, &kept, &reused));
  EXPECT_FALSE(reused) << "another material";
  Model<2> driven = model;
  driven.supports.front().driven = true;
  driven.supports.front().displacement = Vec<2>(0.0, -1e-3);
  EXPECT_TRUE(harness::static_ladder<2>(driven, scene.material, displaced, &kept, &reused));
  EXPECT_FALSE(reused) << "a displaced drive";
  harness::static_ladder<2>(driven, scene.material, fem::ContinuumOptions{}, &kept, &reused);
  EXPECT_TRUE(reused) << "drives held, as the load check holds them";
}

/// The load check's two numbers for the default springs ("auto": fitted) of a scene, with the
/// fit trained on the continuum (`continuum_target`) or on P1 on the mesh (the check alone).
template <int dim> LoadCheck default_springs(const Scene& scene, bool continuum_target) {
  Yardstick yardstick = harness::continuum_yardstick();
  if (!continuum_target) yardstick.plane_target = nullptr, yardstick.solid_target = nullptr;
  const Model<dim> model = build_model<dim>(scene, std::get<Mesh<dim>>(load_mesh(scene)), {}, true, &yardstick);
  EXPECT_EQ(model.net.calibration, "fitted");
  if (continuum_target) {
    EXPECT_EQ(model.net.calibration_target.rfind("the continuum", 0), 0u);
  }
  return {model.net.calibration_load_error, model.net.mesh_fem_load_error, model.net.calibration_yardstick};
}

TEST(FittedSprings, TrainedOnTheContinuumBendThinStripsWhereP1Locks) {
  // 2D strips four and two cells thick (40 x 4, 20 x 2) and a 3D bar two cells thick
  // (10 x 2 x 2), clamped, bent by an end load: P1 on these meshes is 13 %, 37 % and 38 % stiff
  // against the continuum (docs/fidelity.md), and springs fitted to P1 inherit it. Fitted to the
  // continuum's answers they are within the 5 % (measured 0.08 %, 0.28 % and 1.2 %). The bound is the goal the
  // fit is held to; the continuum's own uncertainty (its last refinement's change, 0.04 % and 0.7 %) is far below it.
  const Scene plate = strip(40, 4, "auto");
  const LoadCheck p1_trained_2d = default_springs<2>(plate, false);
  const LoadCheck trained_2d = default_springs<2>(plate, true);
  EXPECT_GT(trained_2d.mesh_fem, 0.1) << "P1 locks on this strip";
  EXPECT_LT(trained_2d.springs, 0.05);
  EXPECT_GT(p1_trained_2d.springs, 0.1) << "a fit to P1 inherits its locking";
  // Two cells thick (the repository's cantilever_step mesh): P1 37 % stiff; trained on the
  // modes the mesh resolves (7 of its 120 free dofs) the fit holds 0.28 % and passes its guard.
  const LoadCheck trained_thin = default_springs<2>(strip(20, 2, "auto"), true);
  EXPECT_GT(trained_thin.mesh_fem, 0.25);
  EXPECT_LT(trained_thin.springs, 0.05);
  const Scene bar = parse_scene(
      "[scene]\nname = \"bar\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"box\", size "
      "= [0.1, 0.02, 0.02], divisions = [10, 2, 2] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity "
      "= 1000.0\n[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.0, 0.0, -1.0e-3]\n",
      "bar.toml", ".");
  const LoadCheck trained_3d = default_springs<3>(bar, true);
  EXPECT_GT(trained_3d.mesh_fem, 0.25) << "P1 locks on this bar";
  EXPECT_LT(trained_3d.springs, 0.05);
}

TEST(FittedSprings, TrainedOnTheContinuumAreCloserToANearlyIncompressibleBlockThanP1) {
  // A 4 cm cube of 4 x 4 x 4 cells at nu = 0.49, bottom clamped, top pressed: P1's tetrahedra
  // lock in volume (18 % stiff); central springs, whose own Poisson ratio is 1/4, cannot hold
  // the material either, but fitted to the continuum they land closer to it than P1 does, which
  // is the goal where P1 locks (measured 6.9 % against 18 %; half of P1's error is the
  // bound, with the continuum itself 2 % from its next refinement: the budget stops it there).
  const Scene block = parse_scene(
      "[scene]\nname = \"block\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"box\", "
      "size = [0.04, 0.04, 0.04], divisions = [4, 4, 4] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.49\n"
      "density = 1000.0\n[[fix]]\ngroup = \"bottom\"\n[[load]]\ngroup = \"top\"\ntotal_force = [0.0, 0.0, -0.1]\n",
      "block.toml", ".");
  const LoadCheck trained = default_springs<3>(block, true);
  EXPECT_GT(trained.mesh_fem, 0.1) << "P1 locks at nu 0.49";
  EXPECT_LT(trained.springs, 0.5 * trained.mesh_fem);
}

TEST(FittedSprings, TrainOnP2OnTheMeshPastTheLaddersBudgetUpToTheFitsOwn) {
  // The fit's target (harness::continuum_target, docs/fidelity.md): the ladder within
  // kContinuumDofs3D; past it P2 on the mesh itself, unrefined, up to kContinuumFitDofs3D (so
  // a graded and a uniform mesh of one body train on the same answers); past that P1 on the
  // mesh. Decided from the mesh's counted dofs before any solve, so nothing is solved here.
  const Yardstick yardstick = harness::continuum_yardstick();
  const MaterialDesc material{5.0e4, 0.3, 1000.0, 1.0, 0.0, 0.0};
  auto target_for = [&](int n) {
    const Scene box = parse_scene(
        "[scene]\nname = \"box\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"box\", size "
        "= [0.04, 0.04, 0.04], divisions = [" +
            std::to_string(n) + ", " + std::to_string(n) + ", " + std::to_string(n) +
            "] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = 1000.0\n[[fix]]\ngroup = "
            "\"bottom\"\n",
        "box.toml", ".");
    const Problem<3> p = build_problem<3>(box, std::get<Mesh<3>>(load_mesh(box)));
    return std::make_pair(fem::continuum_first_dofs(p.mesh), yardstick.target<3>()(p, material));
  };
  const auto [small_dofs, small] = target_for(8);
  ASSERT_LE(small_dofs, fem::kContinuumDofs3D);
  EXPECT_TRUE(small.answers);
  EXPECT_NE(small.how.find("refined until"), std::string::npos) << small.how;
  const auto [mid_dofs, mid] = target_for(14);
  ASSERT_GT(mid_dofs, fem::kContinuumDofs3D);
  ASSERT_LE(mid_dofs, fem::kContinuumFitDofs3D);
  EXPECT_TRUE(mid.answers);
  EXPECT_EQ(mid.key, small.key) << "the same source of answers";
  EXPECT_NE(mid.how.find("P2 on the mesh"), std::string::npos) << mid.how;
  const auto [big_dofs, big] = target_for(17);
  ASSERT_GT(big_dofs, fem::kContinuumFitDofs3D);
  EXPECT_FALSE(big.answers);
  EXPECT_TRUE(big.key.empty());
  EXPECT_EQ(big.how.rfind("P1 FEM on the mesh", 0), 0u) << big.how;
}

TEST(Compare, TheFemReferenceIsTheContinuumAndFemMeshTheScenesOwn) {
  Scene scene = strip(10, 2, "lloyd");
  scene.duration = 0.05;
  scene.output_interval = 0.01;
  scene.solver.dt = 0.01;
  const auto res = harness::run_compare(scene, {"fem-mesh"}, "fem");
  ASSERT_EQ(res.rows.size(), 2u);
  EXPECT_NE(res.reference_note.find("the continuum: P2 refined"), std::string::npos) << res.reference_note;
  double mesh_degree = 0, reference_degree = 0;
  for (const auto& [key, value] : res.rows[0].report.extra)
    if (key == "degree") mesh_degree = value;
  for (const auto& [key, value] : res.rows[1].report.extra)
    if (key == "degree") reference_degree = value;
  EXPECT_EQ(mesh_degree, 1);
  EXPECT_EQ(reference_degree, 2);
  // P1 on this mesh locks (the test above): its run is far from the continuum's.
  EXPECT_GT(res.rows[0].error.displacement_max, 0.2);
  EXPECT_THROW(harness::run_compare(scene, {"fem-mesh"}, "fem-coarse"), InputError);
}

/// The strip above (10 x 2 cells), its load a step at t = 0: it creeps and rings, damped over a
/// retardation time of 2 ms, with the scene's step `dt`.
Scene ringing_strip(double dt) {
  Scene s = strip(10, 2, "lloyd", 0.3);
  s.duration = 0.1;
  s.output_interval = 0.002;
  s.material.retardation_time = 0.002;
  s.solver.dt = dt;
  return s;
}

TEST(Continuum, TheStudysReferenceHoldsItsTimeErrorWithinTheTolerance) {
  // vtb study's FEM reference runs P2 at 4 dt, 2 dt and dt, estimates the order and its time
  // error at dt from the runs' differences, and runs again at dt/2 or dt/4 where that is above
  // 1 %. The claim checked against the truth: the kept run against P2 at an eighth of its step
  // (whose own error is at most 1/8 of the kept one's, order >= 1) differs by at most the
  // tolerance, and the estimate is that difference within a factor 2 (Richardson with the
  // observed order is exact as dt -> 0; here 4 dt reaches 8x the retardation time, the creep's
  // time scale). The strip's load is a step at t = 0: the transient's observed order is below
  // the scheme's 2, which an estimate assuming 2 (or made on P1 on the mesh) missed 2.3-2.6x
  // low on a plate of this kind. With a coarse step the reference halves it; with a fine one it keeps the scene's step.
  constexpr double kTolerance = 0.01;
  for (const double dt : {4e-3, 2.5e-4}) {
    const Scene s = ringing_strip(dt);
    const Model<2> model = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
    Trajectory<2> kept, fine;
    const harness::ReferenceStep step = harness::fem_reference_in_time<2>(s, model, 0, kTolerance, kept);
    fem::FemOptions o = fem::options_from(s.solver);
    o.degree = 2;
    o.dt = step.dt / 8;
    fem::simulate<2>(model, s.material, o, fine, true);
    const double truth = harness::compare(kept, fine).displacement_max;
    std::cout << "scene dt " << dt << ": reference dt " << step.dt << ", " << step.how << "; against dt/8 " << truth
              << "\n";
    EXPECT_GE(step.order, 1.0);
    EXPECT_LE(step.order, 2.0);
    EXPECT_LE(truth, kTolerance);
    EXPECT_GT(step.error, truth / 2);
    EXPECT_LT(step.error, 2 * truth);
    if (dt > 1e-3)
      EXPECT_LT(step.dt, dt) << "the coarse step is halved";
    else
      EXPECT_EQ(step.dt, dt) << "the fine step is kept";
  }
}

} // namespace
} // namespace vtb
