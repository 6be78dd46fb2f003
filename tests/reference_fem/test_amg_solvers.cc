// The FEM's iterative solves (AMG-preconditioned CG, reference_fem/src/amg_krylov.hh) against its
// direct ones on small 3D bodies, linear and neo-Hookean, static and dynamic; and the AMG's
// iteration count across refinements with and without the rigid-body rotations in its
// near-null space. Serial here; under mpirun in mpi_matches_serial.sh.
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/meshes/msh_io.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

namespace vtb {
namespace {

struct Case3 {
  Scene scene;
  Problem<3> problem;
};

Case3 make(const std::string& text) {
  Case3 c{parse_scene(text, "amg_test.toml", std::filesystem::temp_directory_path()), {}};
  c.problem = build_problem<3>(c.scene, std::get<Mesh3>(load_mesh(c.scene)));
  return c;
}

/// A soft block clamped at its base and pressed on a patch of its top (the haptic presses'
/// shape), with the given [solver] lines.
std::string press_scene(const std::string& solver_lines, const std::string& divisions = "[6, 5, 4]") {
  return R"(
[scene]
duration = 0.02
output_interval = 0.01
[mesh]
generate = { shape = "box", size = [0.03, 0.025, 0.02], divisions = )" +
         divisions + R"( }
[material]
young_modulus = 3.0e3
poisson_ratio = 0.45
density = 1000.0
retardation_time = 0.01
[[fix]]
group = "z_min"
[[load]]
box = [[0.01, 0.008, 0.0199], [0.02, 0.017, 0.0201]]
total_force = [0.0, 0.0, -0.05]
[solver]
kind = "fem"
)" + solver_lines;
}

struct Answer {
  Trajectory<3> tr;
  RunReport rep;
};

Answer run(const Case3& c, const std::string& linear_solver) {
  fem::FemOptions o = fem::options_from(c.scene.solver);
  o.linear_solver = linear_solver;
  Answer a;
  a.rep = fem::simulate<3>(c.problem, c.scene.material, o, a.tr, true);
  EXPECT_TRUE(a.rep.stable) << a.rep.failure;
  return a;
}

/// max over samples of |u_it - u_direct| / max |u_direct| over the nodes.
double field_difference(const Trajectory<3>& a, const Trajectory<3>& b) {
  EXPECT_EQ(a.field.size(), b.field.size());
  double worst = 0;
  for (std::size_t k = 0; k < a.field.size() && k < b.field.size(); ++k) {
    const double scale = b.field[k].cwiseAbs().maxCoeff();
    if (scale > 0) worst = std::max(worst, (a.field[k] - b.field[k]).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

double extra(const RunReport& r, const std::string& key) {
  for (const auto& [k, v] : r.extra)
    if (k == key) return v;
  ADD_FAILURE() << "no " << key;
  return std::nan("");
}

// Tolerances: CG stops at a residual of 1e-12 of the right-hand side; the error is at most
// cond(A) times that. For P2 on these blocks cond(A) (the eliminated stiffness) is of order
// (L / h)^2 (E / min diagonal) ~ 1e3-1e4, so 1e-8 of the answer holds with a margin of 10-100.
TEST(FemAmg, TheIterativeStaticSolveIsTheDirectOne) {
  for (int degree : {1, 2}) {
    const Case3 c = make(press_scene("static = true\ndegree = " + std::to_string(degree) + "\n"));
    const Answer direct = run(c, "direct"), cg = run(c, "cg");
    EXPECT_EQ(extra(direct.rep, "iterative_solver"), 0);
    EXPECT_EQ(extra(cg.rep, "iterative_solver"), 1);
    const double d = field_difference(cg.tr, direct.tr);
    std::cout << "P" << degree << " static: iterative vs direct " << d << ", " << extra(cg.rep, "krylov_iterations_max")
              << " iterations\n";
    EXPECT_LT(d, 1e-8);
  }
}

TEST(FemAmg, TheIterativeTransientIsTheDirectOne) {
  // Generalized-alpha: one matrix, many right-hand sides; every step's solve to 1e-12.
  const Case3 c = make(press_scene("dt = 0.001\ndegree = 2\n"));
  const Answer direct = run(c, "direct"), cg = run(c, "cg");
  EXPECT_LT(field_difference(cg.tr, direct.tr), 1e-8);
  EXPECT_EQ(extra(cg.rep, "amg_setups"), 1); // one hierarchy for every step (the matrix is constant)
  EXPECT_EQ(extra(cg.rep, "krylov_solves"), 20);
}

TEST(FemAmg, TheIterativeNeoHookeanPressIsTheDirectOne) {
  // Static load stepping with Newton; the tangent's corrections solved to 1e-8 of their
  // residual, Newton's own test (1e-9 of the first residual, or an update of 1e-10) ends both
  // runs; Newton's last step is quadratic, so the two answers agree far below either stop.
  const Case3 c = make(press_scene("static = true\ndegree = 2\nkinematics = \"neo-hookean\"\n"));
  const Answer direct = run(c, "direct"), cg = run(c, "cg");
  EXPECT_EQ(extra(direct.rep, "iterative_solver"), 0);
  EXPECT_LT(field_difference(cg.tr, direct.tr), 1e-8);
  // The hierarchy is reused across Newton steps and increments.
  EXPECT_LT(extra(cg.rep, "amg_setups"), extra(cg.rep, "krylov_solves"));
}

/// CG's iterations for a slender clamped bar under a tip load (bending: the mode a coarse space
/// without rotations cannot represent) at `refinements` uniform refinements of P1: 3,075 dofs
/// on the mesh, above the AMG's coarsest level (2,000 dofs, solved directly), to 150k.
long bar_iterations(int refinements, bool rotations) {
  const Case3 c = make(R"(
[scene]
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [0.2, 0.02, 0.02], divisions = [40, 4, 4] }
[material]
young_modulus = 1.0e5
poisson_ratio = 0.3
density = 1000.0
[[fix]]
group = "x_min"
[[load]]
group = "x_max"
total_force = [0.0, 0.0, -1.0]
[solver]
kind = "fem"
static = true
linear_solver = "cg"
refinements = )" + std::to_string(refinements) +
                       "\n");
  fem::FemOptions o = fem::options_from(c.scene.solver);
  o.amg_rotations = rotations;
  Trajectory<3> tr;
  const RunReport r = fem::simulate<3>(c.problem, c.scene.material, o, tr, false);
  EXPECT_TRUE(r.stable);
  return static_cast<long>(extra(r, "krylov_iterations_max"));
}

TEST(FemAmg, RigidBodyModesBoundTheIterations) {
  // Smoothed aggregation with elasticity's six rigid-body modes is mesh-independent: its
  // iteration count stays nearly flat under refinement (h -> h / 4: 64x the cells). With the
  // translations alone the coarse spaces miss bending and the count grows.
  long with[3], without[3];
  for (int r = 0; r < 3; ++r) {
    with[r] = bar_iterations(r, true);
    without[r] = bar_iterations(r, false);
    std::cout << "refinements " << r << ": " << with[r] << " iterations with rotations, " << without[r] << " without\n";
  }
  EXPECT_LE(with[2], 2 * with[0] + 5) << "bounded: at most doubled across two refinements";
  EXPECT_GT(without[2], 2 * with[2]) << "the rotations are what bound it";
}

TEST(FemAmg, AutoPicksTheIterativeSolveOnLarge3DSystems) {
  EXPECT_FALSE(fem::iterative_by_default(3, fem::kIterativeFromDofs3D, 1));
  EXPECT_TRUE(fem::iterative_by_default(3, fem::kIterativeFromDofs3D + 1, 1));
  EXPECT_FALSE(fem::iterative_by_default(2, fem::kIterativeFromDofs3D + 1, 1));
  // Newton's tangent, refactorised every iteration, goes iterative far earlier in 3D only.
  EXPECT_FALSE(fem::iterative_by_default(3, fem::kIterativeTangentFromDofs3D, 1, true));
  EXPECT_TRUE(fem::iterative_by_default(3, fem::kIterativeTangentFromDofs3D + 1, 1, true));
  EXPECT_FALSE(fem::iterative_by_default(2, fem::kIterativeTangentFromDofs3D + 1, 1, true));
}

TEST(FemAmg, AnUnknownLinearSolverIsRefusedInOneLine) {
  fem::FemOptions o;
  o.linear_solver = "gmres";
  try {
    fem::check_options(o);
    FAIL() << "accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("[solver].linear_solver"), std::string::npos) << e.what();
  }
}

} // namespace
} // namespace vtb
