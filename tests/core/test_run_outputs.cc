// vtb run's files: names, headers, reactions in balance with the loads at rest.
#include "support/fresh_dir.hh"
#include "support/small_models.hh"
#include "vtb/problem/cell_fields.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/simulation.hh"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace vtb {
namespace {

TEST(RunOutputs, WritesTheContractFilesAndBalancedReactions) {
  const std::string text = test::plate_scene(8, 2, R"(
[[fix]]
name = "clamp"
group = "left"
[[load]]
name = "pull"
group = "right"
total_force = [0.3, -0.1]
[[probe]]
name = "tip"
point = [0.2, 0.025]
[solver]
kind = "implicit-euler"
dt = 2e-3
)",
                                             0.05, "0.2, 0.05", 20.0);
  const Scene scene = parse_scene(text, "plate.toml", ".");
  const test::FreshDir fresh;
  const auto dir = fresh / "out";
  const RunReport r = run_scene(scene, dir);
  ASSERT_TRUE(r.stable);
  const std::string probes = test::read_text(dir / "probes.csv"), reactions = test::read_text(dir / "reactions.csv");
  EXPECT_EQ(probes.substr(0, probes.find('\n')), "t,probe,ux,uy,uz");
  EXPECT_EQ(reactions.substr(0, reactions.find('\n')), "t,region,fx,fy,fz");
  EXPECT_EQ(std::count(probes.begin(), probes.end(), '\n'), 1 + 101) << "header + samples at 0, 0.01, ..., 1";
  const auto j = nlohmann::json::parse(test::read_text(dir / "summary.json"));
  for (const char* key : {"solver", "nodes", "springs", "dt", "steps", "precompute_seconds", "step_seconds",
                          "total_seconds", "stable", "max_strain"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["steps"], 500);
  // Each probe's node and how far it is from the probe's point (here the tip node itself).
  ASSERT_EQ(j["probes"].size(), 1u);
  EXPECT_EQ(j["probes"][0]["name"], "tip");
  EXPECT_TRUE(j["probes"][0]["node"].is_number_integer());
  EXPECT_NEAR(j["probes"][0]["distance"].get<double>(), 0.0, 1e-15);
  EXPECT_TRUE(j["step_seconds"].contains("median") && j["step_seconds"].contains("p99"));
  // At rest the clamp's reaction balances the load: R + F = 0. Mass damping 20/s makes every
  // mode decay at least like e^(-10 t) (gamma/2), so after 1 s the residual is < 1e-4 x
  // the load; the slowest (bending) mode is overdamped and decays far faster. We allow 1e-4.
  const std::string last = reactions.substr(reactions.rfind("1,clamp,"));
  double fx = 0, fy = 0;
  std::sscanf(last.c_str(), "1,clamp,%lf,%lf", &fx, &fy);
  EXPECT_NEAR(fx, -0.3, 1e-4 * 0.3);
  EXPECT_NEAR(fy, 0.1, 1e-4 * 0.3);
  EXPECT_FALSE(std::filesystem::exists(dir / "summary.json.part"));
}

/// A plate clamped on the left and pulled on the right by 0.3 N, run with `solver` (the
/// [solver] table's lines) into dir; returns the report and summary.json.
std::pair<RunReport, nlohmann::json> run_pulled_plate(const std::string& solver, const std::filesystem::path& dir) {
  const std::string text = test::plate_scene(
      8, 2, "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.3, 0.0]\n[solver]\n" + solver);
  const RunReport r = run_scene(parse_scene(text, "plate.toml", "."), dir);
  return {r, nlohmann::json::parse(test::read_text(dir / "summary.json"))};
}

TEST(RunOutputs, UnstableRunIsReportedNotCrashed) {
  const test::FreshDir fresh;
  const auto [r, j] = run_pulled_plate("kind = \"explicit\"\ndt = 1e-3\n", fresh / "out");
  EXPECT_FALSE(r.stable);
  // The explicit scheme's failure names its stability limit (the user's next step).
  EXPECT_NE(r.failure.find("times the explicit scheme's stability limit"), std::string::npos) << r.failure;
  EXPECT_EQ(j["stable"], false);
  EXPECT_LT(j["steps"].get<long>(), 1000);
}

TEST(RunOutputs, SummarySaysWhichFilterAutoPicked) {
  // No filter key: the scene's default `auto`; on a 2D plate it runs the lag-free tensor filter.
  const test::FreshDir fresh;
  const auto [r, j] = run_pulled_plate("kind = \"filtered\"\ndt = 1e-2\n", fresh / "out");
  ASSERT_TRUE(r.stable);
  EXPECT_EQ(j["filter"], "tensor");
  EXPECT_EQ(j["filter_requested"], "auto");
}

TEST(RunOutputs, AStepBudgetCountsTheStepsOverItAndPicksTheMostAccurateFilterThatFits) {
  // [solver] step_budget: with a budget no step can miss (1000 s) every step is within it and
  // auto runs the most accurate candidate, the tensor filter; with one no step can meet
  // (1e-12 s) every step is over it, and auto runs the cheapest filter it measured, saying so.
  // Which one that is depends on the clock; that it is one of the 2D candidates does not.
  const test::FreshDir fresh;
  const auto [r, j] = run_pulled_plate("kind = \"filtered\"\ndt = 1e-2\nstep_budget = 1000.0\n", fresh / "loose");
  ASSERT_TRUE(r.stable);
  EXPECT_EQ(j["filter"], "tensor");
  EXPECT_EQ(j["filter_requested"], "auto");
  EXPECT_EQ(j["steps_over_budget"], 0);
  EXPECT_EQ(j["over_budget_share"], 0.0);
  EXPECT_NE(j["filter_reason"].get<std::string>().find("fits the step budget"), std::string::npos) << j.dump();
  const auto [t, k] = run_pulled_plate("kind = \"filtered\"\ndt = 1e-2\nstep_budget = 1e-12\n", fresh / "tight");
  ASSERT_TRUE(t.stable);
  EXPECT_EQ(k["steps_over_budget"], k["steps"]);
  EXPECT_EQ(k["over_budget_share"], 1.0);
  EXPECT_TRUE(k["filter"] == "tensor" || k["filter"] == "full") << k.dump();
  EXPECT_EQ(k["filter_reason"].get<std::string>().rfind("no filter's measured step fits", 0), 0u) << k.dump();
  // A named filter is run as named, the budget only counted; without a budget nothing is said.
  const auto [n, m] =
      run_pulled_plate("kind = \"filtered\"\nfilter = \"full\"\ndt = 1e-2\nstep_budget = 1e-12\n", fresh / "named");
  EXPECT_EQ(m["filter"], "full");
  EXPECT_FALSE(m.contains("filter_reason"));
  EXPECT_EQ(m["steps_over_budget"], m["steps"]);
  const auto [u, w] = run_pulled_plate("kind = \"filtered\"\ndt = 1e-2\n", fresh / "none");
  EXPECT_FALSE(w.contains("step_budget"));
  EXPECT_FALSE(w.contains("steps_over_budget"));
}

TEST(RunOutputs, AStepBudgetWithAVolumeTermPicksAmongTheFiltersThatTakeIt) {
  // The tensor filter has no cell blocks for the volume term, and refuses it by name; auto
  // within a budget (what a haptic session's physics does) must not pick it for such springs.
  // With a budget every step meets, the most accurate filter that takes the term: full in 2D.
  const test::FreshDir fresh;
  const auto [r, j] =
      run_pulled_plate("kind = \"filtered\"\nsprings = \"volume\"\ndt = 1e-2\nstep_budget = 1000.0\n", fresh / "loose");
  ASSERT_TRUE(r.stable);
  EXPECT_EQ(j["filter"], "full") << j.dump();
  EXPECT_EQ(j["filter_requested"], "auto");
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(RunOutputs, MaxStrainIsTheFemsDefinitionForEverySolver) {
  // max_strain is the largest principal small strain of the P1 field (as the FEM computes it
  // at its cells' centres): exact for a uniform strain on any mesh, zero for a translation;
  // the spring measure max |l/L0 - 1| is reported beside it as max_spring_strain.
  const Mesh2 m = generate_rectangle({0.2, 0.05}, {8, 2});
  Nodal<2> u(2, m.num_nodes());
  for (int i = 0; i < m.num_nodes(); ++i) u.col(i) << 0.003 * m.points(0, i) - 0.001 * m.points(1, i), 0.01;
  // grad u = [[0.003, -0.001], [0, 0]]: eps = [[0.003, -0.0005], [-0.0005, 0]], whose largest
  // eigenvalue is 0.0015 + sqrt(0.0015^2 + 0.0005^2), on every cell.
  EXPECT_NEAR(max_small_strain<2>(m, u), 0.0015 + std::sqrt(0.0015 * 0.0015 + 0.0005 * 0.0005), 1e-15);
  u.row(0).setConstant(0.02);
  EXPECT_EQ(max_small_strain<2>(m, u), 0.0);
  const RunReport r = [] {
    Model<2> model = test::model_from(
        test::plate_scene(8, 2, "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.2, 0.0]\n"));
    model.duration = 0.1;
    model.output_interval = 0.01;
    Trajectory<2> tr;
    IntegratorOptions o;
    o.kind = "implicit-euler";
    return simulate(model, o, tr);
  }();
  const auto j = nlohmann::json::parse(summary_json(r, "plate"));
  EXPECT_GT(j["max_strain"].get<double>(), 0.0);
  EXPECT_GT(j["max_spring_strain"].get<double>(), 0.0);
  // The springs' static error on the scene's own loads (load_check.hh, measured in its own
  // test) goes with the run (8.5 % for the fitted springs on this plate two cells thick, past
  // the 5 % at which `vtb run` prints a line about it).
  ASSERT_TRUE(j.contains("calibration_load_error"));
  EXPECT_EQ(j["calibration_load_error"].get<double>(), r.calibration_load_error);
  EXPECT_GT(r.calibration_load_error, 0.0);
}

TEST(RunOutputs, MaxRotationIsTheCellsPolarAngle) {
  // A rigid rotation by theta (u = (R - I) X) has F = R on every cell: max_rotation = theta
  // to round-off, in 2D and 3D, while a pure stretch (F symmetric) has none; a stretch after
  // the rotation (F = R S) still gives theta (the polar decomposition separates them).
  const double theta = 0.3;
  const Mesh2 m = generate_rectangle({0.2, 0.05}, {8, 2});
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(theta).toRotationMatrix();
  const Eigen::Matrix2d S = (Eigen::Matrix2d() << 1.02, 0.01, 0.01, 0.99).finished();
  Nodal<2> u = (R - Eigen::Matrix2d::Identity()) * m.points;
  EXPECT_NEAR(max_rotation<2>(m, u), theta, 1e-12);
  u = (R * S - Eigen::Matrix2d::Identity()) * m.points;
  EXPECT_NEAR(max_rotation<2>(m, u), theta, 1e-12);
  u = (S - Eigen::Matrix2d::Identity()) * m.points;
  EXPECT_NEAR(max_rotation<2>(m, u), 0.0, 1e-12);
  const Mesh3 b = generate_box({0.1, 0.03, 0.03}, {3, 2, 2});
  const Eigen::Matrix3d R3 = Eigen::AngleAxisd(theta, Eigen::Vector3d(1, 2, 2).normalized()).toRotationMatrix();
  const Nodal<3> u3 = (R3 - Eigen::Matrix3d::Identity()) * b.points;
  EXPECT_NEAR(max_rotation<3>(b, u3), theta, 1e-12);
  // Any deformation, against the polar rotation of F's SVD on each cell (F = U S V^T, R = U V^T,
  // the closest proper rotation where a cell is inverted), its angle by atan2 as well: random
  // node motions of up to a cell's size (rotations to past 1 rad, some cells inverted). Both are
  // R to round-off, so the angles agree to 1e-12.
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> r(-1.0, 1.0);
  for (double size : {1e-4, 1e-2, 0.5}) {
    Nodal<3> w(3, b.num_nodes());
    for (Eigen::Index k = 0; k < w.size(); ++k) w.data()[k] = size * 0.03 * r(gen);
    double want = 0;
    for (const auto& cell : b.cells) {
      Eigen::Matrix3d Dm, Ds;
      for (int k = 0; k < 3; ++k) {
        Dm.col(k) = b.points.col(cell[k + 1]) - b.points.col(cell[0]);
        Ds.col(k) = Dm.col(k) + w.col(cell[k + 1]) - w.col(cell[0]);
      }
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Ds * Dm.inverse(), Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d U = svd.matrixU();
      if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) *= -1;
      const Eigen::Matrix3d Rc = U * svd.matrixV().transpose();
      const Eigen::Vector3d axial(Rc(2, 1) - Rc(1, 2), Rc(0, 2) - Rc(2, 0), Rc(1, 0) - Rc(0, 1));
      want = std::max(want, std::atan2(0.5 * axial.norm(), 0.5 * (Rc.trace() - 1)));
    }
    EXPECT_NEAR(max_rotation<3>(b, w), want, 1e-12) << "motions of " << size << " cells";
    // The largest small strain, by the closed form, against the iterative eigensolver: equal to
    // round-off of the strain's size.
    double strain = 0;
    for (const auto& cell : b.cells) {
      Eigen::Matrix3d Dm, Du;
      for (int k = 0; k < 3; ++k) {
        Dm.col(k) = b.points.col(cell[k + 1]) - b.points.col(cell[0]);
        Du.col(k) = w.col(cell[k + 1]) - w.col(cell[0]);
      }
      const Eigen::Matrix3d g = Du * Dm.inverse(), eps = 0.5 * (g + g.transpose());
      strain = std::max(strain, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(eps, Eigen::EigenvaluesOnly)
                                    .eigenvalues()
                                    .cwiseAbs()
                                    .maxCoeff());
    }
    EXPECT_NEAR(max_small_strain<3>(b, w), strain, 1e-13 * strain);
  }
  // The regime note: silent inside the limits, names the rotation beyond them.
  EXPECT_EQ(small_strain_regime_note(0.05, 0.005), "");
  EXPECT_NE(small_strain_regime_note(0.3, 0.005).find("max rotation 0.3 rad"), std::string::npos);
  EXPECT_NE(small_strain_regime_note(0.01, 0.02).find("max strain 0.02"), std::string::npos);
}

} // namespace
} // namespace vtb
