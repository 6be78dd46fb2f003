// The volume networks' fit trains on the scene's own loads beside the modes (FitTarget::own_loads,
// FitOptions::own_load; docs/volume_term.md, "Trained on the scene's loads"): the network then
// answers that load closer to its target, answers loads it never saw as well as before, and the
// cache keys the load's shape, not its size.
#include "support/fresh_dir.hh"
#include "support/static_answers.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/fitted_springs.hh"
#include "vtb/springs/spring_network.hh"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>

namespace vtb {
namespace {

struct Block {
  Mesh3 mesh = generate_box({0.04, 0.04, 0.02}, {8, 8, 4});
  std::vector<int> supports; ///< z = 0, sorted
  std::vector<bool> fixed;
  Block() {
    fixed.assign(static_cast<std::size_t>(mesh.num_nodes()), false);
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (mesh.points(2, v) < 1e-9) supports.push_back(v), fixed[static_cast<std::size_t>(v)] = true;
  }
  /// A local press: `force` shared by the top nodes within `radius` of (x, y).
  Eigen::VectorXd press(double x, double y, double radius, const Vec<3>& force) const {
    std::vector<int> under;
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (mesh.points(2, v) > 0.02 - 1e-9 && std::hypot(mesh.points(0, v) - x, mesh.points(1, v) - y) <= radius)
        under.push_back(v);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
    for (const int v : under) f.segment<3>(3 * v) = force / static_cast<double>(under.size());
    return f;
  }
  /// P1 on the mesh, clamped at z = 0: every column of `loads` answered (the test's continuum).
  Eigen::MatrixXd p1(const Eigen::MatrixXd& loads, double E, double nu) const {
    const test::SpMat K = fem_stiffness_matrix(mesh, E, nu, 1.0);
    Eigen::MatrixXd u(loads.rows(), loads.cols());
    for (Eigen::Index c = 0; c < loads.cols(); ++c) u.col(c) = test::clamped_solve(K, loads.col(c), fixed, 3);
    return u;
  }
  /// The target a run gives: P1's answers to the modes, and to `own` when it is not empty.
  FitTarget target(const Eigen::VectorXd& own) const {
    FitTarget t;
    t.key = "test-p1";
    t.how = "P1 (test)";
    t.answers = [this](const Eigen::MatrixXd& F, double E, double nu, double) { return p1(F, E, nu); };
    if (own.size() > 0) {
      t.own_loads = own;
      t.own_answers = [this, own](double E, double nu, double) { return p1(own, E, nu); };
    }
    return t;
  }
  /// The network's clamped static answer to f against P1's (relative L2 over all nodes).
  double error(const SpringNetwork<3>& net, const Eigen::VectorXd& f, double E, double nu) const {
    const Nodal<3> zero = Nodal<3>::Zero(3, mesh.num_nodes());
    const Eigen::VectorXd u = test::clamped_solve(-force_jacobians<3>(net, zero, false).K, f, fixed, 3);
    const Eigen::VectorXd ufem = p1(f, E, nu);
    return (u - ufem).norm() / ufem.norm();
  }
};

TEST(OwnLoadTraining, FitsTheScenesLoadAndKeepsTheLoadsItNeverSaw) {
  // A 40 x 40 x 20 mm block of 405 nodes clamped at its base, pressed on its top by a load
  // about two cells wide (the deep press's case: the modes a network is trained on barely hold
  // a load one or two cells across). Trained on that load as well, the network's answer to it
  // moves toward the target (on the reproduction's deep-press layer 16 % -> 7.2 % at nu 0.3,
  // 12.4 % -> 6.5 % at nu 0.45); an off-centre press, a sideways one and the whole top's shear,
  // which neither fit saw, stay where the modes alone put them. The bounds: the trained load at
  // most 0.8x its modes-only error (it is one of the fit's ~30 pairs, at twice a mode's
  // weight, so it cannot reach zero), the unseen ones within a point of the modes-only fit's
  // (measured: at most 0.7 point worse here, 0.5 on the deep-press layer).
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  const Block b;
  const double E = 5.0e3;
  const Eigen::VectorXd own = b.press(0.02, 0.02, 0.006, Vec<3>(0, 0, -0.1));
  const Eigen::VectorXd off = b.press(0.01, 0.03, 0.006, Vec<3>(0, 0, -0.1));
  const Eigen::VectorXd side = b.press(0.02, 0.02, 0.006, Vec<3>(0.1, 0, 0));
  const Eigen::VectorXd shear = b.press(0.02, 0.02, 1.0, Vec<3>(0.1, 0, 0));
  for (const double nu : {0.3, 0.45}) {
    const MaterialDesc mat{E, nu, 1000, 1.0, 0, 0};
    const SpringNetwork<3> trained = build_network(b.mesh, mat, "fitted-nodal", b.supports, {}, b.target(own));
    const SpringNetwork<3> modes = build_network(b.mesh, mat, "fitted-nodal", b.supports, {}, b.target({}));
    ASSERT_EQ(trained.calibration, "fitted-nodal");
    ASSERT_EQ(modes.calibration, "fitted-nodal");
    const double seen = b.error(trained, own, E, nu), seen_before = b.error(modes, own, E, nu);
    std::cout << "nu " << nu << ": the trained load " << seen_before << " -> " << seen;
    EXPECT_LT(seen, 0.8 * seen_before) << "nu " << nu;
    for (const auto& [name, f] : {std::pair{"off-centre", &off}, {"sideways", &side}, {"shear", &shear}}) {
      const double now = b.error(trained, *f, E, nu), before = b.error(modes, *f, E, nu);
      std::cout << ", " << name << " " << before << " -> " << now;
      EXPECT_LT(now, before + 0.01) << "nu " << nu << ", " << name;
    }
    std::cout << "\n";
  }
  // The springs alone (`fitted`, the paper's network and auto's) do not train on it.
  const MaterialDesc mat{E, 0.3, 1000, 1.0, 0, 0};
  const SpringNetwork<3> pair = build_network(b.mesh, mat, "fitted", b.supports, {}, b.target(own));
  const SpringNetwork<3> pair_modes = build_network(b.mesh, mat, "fitted", b.supports, {}, b.target({}));
  EXPECT_EQ(pair.stiffness, pair_modes.stiffness);
  ::unsetenv("VTB_CACHE_DIR");
}

TEST(OwnLoadTraining, IsCachedByTheLoadsShapeNotItsSize) {
  // The fit scales the load to its modes' size, so a scene pressed harder reads the same fit
  // back (the key holds the load at unit length to 2^-32: a scaled load differs in its last
  // bits, and a fit run again from such a load may stop one step apart); a load elsewhere is
  // another fit.
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  const Block b;
  const MaterialDesc mat{5.0e3, 0.3, 1000, 1.0, 0.05, 0};
  const Eigen::VectorXd own = b.press(0.02, 0.02, 0.006, Vec<3>(0, 0, -0.1));
  const SpringNetwork<3> first = build_network(b.mesh, mat, "fitted-nodal", b.supports, {}, b.target(own));
  EXPECT_FALSE(first.calibration_cached);
  const SpringNetwork<3> harder = build_network(b.mesh, mat, "fitted-nodal", b.supports, {}, b.target(3.0 * own));
  EXPECT_TRUE(harder.calibration_cached);
  EXPECT_EQ(harder.stiffness, first.stiffness);
  EXPECT_EQ(harder.volume.node_stiffness, first.volume.node_stiffness);
  const SpringNetwork<3> elsewhere = build_network(b.mesh, mat, "fitted-nodal", b.supports, {},
                                                   b.target(b.press(0.01, 0.03, 0.006, Vec<3>(0, 0, -0.1))));
  EXPECT_FALSE(elsewhere.calibration_cached);
  EXPECT_NE(elsewhere.stiffness, first.stiffness);
  ::unsetenv("VTB_CACHE_DIR");
}

} // namespace
} // namespace vtb
