// springs = "fitted": the network identified from the P1 FEM on the same mesh, checked on
// static cases that the fit never saw (its training loads are the free mesh's modes).
#include "support/fresh_dir.hh"
#include "support/static_answers.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/cgal_generate.hh"
#endif
#include "vtb/base/input_error.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/fitted_cache.hh"
#include "vtb/springs/fitted_springs.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/springs/model.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

namespace vtb {
namespace {

using test::clamped_solve;
using test::SpMat;

template <int dim> SpMat spring_matrix(const Mesh<dim>& mesh, const Eigen::VectorXd& k) {
  return test::network_matrix(mesh, k);
}

/// A cantilever clamped where coordinate `axis` is least, with a load spread over the nodes
/// where it is largest: the relative L2 error of the springs' linear static answer against the
/// P1 FEM's, over all nodes.
template <int dim>
double cantilever_error(const Mesh<dim>& mesh, const Eigen::VectorXd& k, double E, double nu, double t,
                        const Vec<dim>& force, int axis = 0) {
  const double low = mesh.points.row(axis).minCoeff(), high = mesh.points.row(axis).maxCoeff();
  std::vector<bool> fixed(static_cast<std::size_t>(mesh.num_nodes()));
  Eigen::VectorXd f = Eigen::VectorXd::Zero(dim * mesh.num_nodes());
  for (int v = 0; v < mesh.num_nodes(); ++v) {
    fixed[static_cast<std::size_t>(v)] = mesh.points(axis, v) < low + 1e-9;
    if (mesh.points(axis, v) > high - 1e-9) f.segment<dim>(dim * v) = force;
  }
  return test::static_error(mesh, k, nullptr, E, nu, t, fixed, f);
}

/// A patch of equilateral triangles (a triangular lattice cut to a parallelogram).
Mesh2 equilateral_patch(int nx, int ny) {
  Mesh2 m;
  m.points.resize(2, (nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.points.col(j * (nx + 1) + i) << i + 0.5 * j, j * std::sqrt(3.0) / 2;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      m.cells.push_back({a, b, c});
      m.cells.push_back({b, d, c});
    }
  return m;
}

TEST(FittedSprings, FindTheExactNetworkWhereOneExists) {
  // Equilateral triangles at nu = 1/3: the spring element equals the P1 element, so a network
  // with K_springs = K_fem exists (Lloyd's). Started from springs scaled by random factors in
  // [0.5, 2] and with no pull toward Lloyd, the fit must find an exact network: the residual
  // on its training modes and a held-out cantilever agree with the FEM to the LM/CG tolerance.
  const Mesh2 m = equilateral_patch(6, 4);
  const double E = 1.0e4, nu = 1.0 / 3.0, t = 0.01;
  FitOptions o;
  o.pull = 0;
  o.tolerance = 1e-12;
  o.max_iterations = 60;
  const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, t);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> factor(std::log(0.5), std::log(2.0));
  o.start = lloyd;
  for (Eigen::Index s = 0; s < lloyd.size(); ++s) o.start[s] *= std::exp(factor(rng));
  EXPECT_GT(cantilever_error<2>(m, o.start, E, nu, t, {1, 0}, 1), 0.05) << "the start is far from the FEM";
  FitReport rep;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, t, o, &rep);
  EXPECT_LT(rep.lloyd_residual, 1e-10);
  EXPECT_LT(rep.fitted_residual, 1e-6) << rep.iterations << " " << rep.cg_iterations;
  EXPECT_LT(cantilever_error<2>(m, k, E, nu, t, {1, 0}, 1), 1e-5);
  EXPECT_LT(cantilever_error<2>(m, k, E, nu, t, {0, 1}, 1), 1e-5);
}

TEST(FittedSprings, BringTheUnionJackStripWithinFivePercentOfTheFem) {
  // On the union-jack lattice no network is exact and Lloyd is 1.3x too stiff (lattice theory,
  // E_eff / E = 1.305). The fit never sees these loads (its training loads are the free
  // strip's modes); the goal for a fitted network at nu = 1/3 is 5 % over all nodes.
  const Mesh2 m = generate_rectangle({0.2, 0.02}, {40, 4});
  const double E = 5.0e4, nu = 1.0 / 3.0, t = 0.001;
  FitReport rep;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, t, {}, &rep);
  const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, t);
  EXPECT_LT(rep.fitted_residual, 0.5 * rep.lloyd_residual);
  for (const Vec<2>& force : {Vec<2>(1e-4, 0), Vec<2>(0, 1e-6)}) {
    const double fitted = cantilever_error<2>(m, k, E, nu, t, force);
    const double before = cantilever_error<2>(m, lloyd, E, nu, t, force);
    EXPECT_LT(fitted, 0.05) << "load " << force.transpose() << ", lloyd " << before;
    EXPECT_LT(fitted, 0.5 * before);
  }
  EXPECT_GE(k.minCoeff(), 0.0);
}

TEST(FittedSprings, BringAnUnstructured3DSlabWithinFivePercentOfTheFem) {
  // 3D at nu = 1/4 (the Cauchy value of a central-force lattice) on the canonical CGAL Mesh_3
  // slab (458 nodes): Lloyd's per-element fit is off by 18 % or more on the clamped slab; the
  // fitted network, which never saw a clamp or these loads, is held to the 5 % goal.
  const auto mesh = read_msh(std::filesystem::path(VTB_SOURCE_DIR) / "meshes/data/slab_500.msh");
  const Mesh3& m = std::get<Mesh3>(mesh);
  const double E = 5.0e4, nu = 0.25;
  FitReport rep;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, 1.0, {}, &rep);
  const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, 1.0);
  EXPECT_LT(rep.fitted_residual, 0.5 * rep.lloyd_residual);
  for (const Vec<3>& force : {Vec<3>(1e-3, 0, 0), Vec<3>(0, 0, -1e-5), Vec<3>(0, 1e-5, 0)}) {
    const double fitted = cantilever_error<3>(m, k, E, nu, 1.0, force);
    const double before = cantilever_error<3>(m, lloyd, E, nu, 1.0, force);
    EXPECT_LT(fitted, 0.05) << "load " << force.transpose() << ", lloyd " << before;
    EXPECT_LT(fitted, 0.5 * before) << "load " << force.transpose();
  }
}

TEST(FittedSprings, HoldCooksMembraneOnItsClampWithinFivePercent) {
  // Cook's membrane on a 16 x 16 union-jack grid mapped onto the trapezoid (triangles
  // stretched up to 3:1 toward the loaded edge), clamped at x = 0, nu = 1/3: Lloyd's
  // per-element fit leaves near-mechanisms there (110 %), van Gelder's is 13 % off. The fit,
  // trained on the clamped body, is held to the 5 % goal under the shear that defines the
  // benchmark, a load it never saw.
  Mesh2 m = generate_rectangle({48.0, 44.0}, {16, 16});
  for (Eigen::Index v = 0; v < m.points.cols(); ++v) {
    const double x = m.points(0, v), y = m.points(1, v);
    m.points(1, v) = 44.0 * x / 48.0 + y * (44.0 - 28.0 * x / 48.0) / 44.0;
  }
  const double E = 1.0, nu = 1.0 / 3.0;
  FitOptions o;
  o.supports = m.groups.at("left").nodes;
  FitReport rep;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, 1.0, o, &rep);
  const double fitted = cantilever_error<2>(m, k, E, nu, 1.0, Vec<2>(0, 1.0 / 17));
  const double vg = cantilever_error<2>(m, van_gelder_stiffness(m, E, 1.0), E, nu, 1.0, Vec<2>(0, 1.0 / 17));
  std::cout << "Cook: van Gelder " << vg << ", fitted " << fitted << " (" << rep.iterations << " steps, " << rep.chosen
            << ")\n";
  EXPECT_LT(fitted, 0.05);
}

TEST(FittedSprings, StopOnceTheHeldOutModesStopImprovingAndTellTheirProgress) {
  // The early stop (here FitOptions::patience 2; the default beyond kEarlyStopDofs free dofs is
  // 1) ends the fit when its held-out modes and its residual stop improving; run to the
  // residual's tolerance (patience 0, the default on this 458-node slab) the same fit takes
  // more steps (6 against 36 here, at the tolerance of 1e-5 below). The stopped fit must still meet the 5 % goal on the
  // clamped slab's loads, which it never saw, and the progress callback hears the modes, the steps and one "done" at
  // the end.
  const auto mesh = read_msh(std::filesystem::path(VTB_SOURCE_DIR) / "meshes/data/slab_500.msh");
  const Mesh3& m = std::get<Mesh3>(mesh);
  const double E = 5.0e4, nu = 0.25;
  FitOptions early;
  early.supports = m.groups.at("left").nodes;
  early.patience = 2;
  // A tolerance far below the default's: only the held-out modes can end the early fit
  // sooner. At the default 5e-3 this slab's fit ends on its tolerance after 7 steps, and
  // whether the held-out test fires a step before depends on the last digits of the
  // machine's BLAS (it did on one CI machine and not on the next).
  early.tolerance = 1e-5;
  std::vector<std::string> stages;
  early.progress = [&](const char* stage, int step, int steps) {
    EXPECT_LE(step, steps);
    if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
  };
  FitOptions full = early;
  full.patience = 0;
  full.progress = {};
  FitReport rep_early, rep_full;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, 1.0, early, &rep_early);
  fitted_stiffness(m, E, nu, 1.0, full, &rep_full);
  std::cout << "steps " << rep_early.iterations << " vs " << rep_full.iterations << ", held-out "
            << rep_early.validation_fitted << " vs " << rep_full.validation_fitted << "\n";
  EXPECT_LT(rep_early.iterations, rep_full.iterations);
  EXPECT_EQ(stages, (std::vector<std::string>{"modes", "fit", "done"}));
  for (const Vec<3>& force : {Vec<3>(1e-3, 0, 0), Vec<3>(0, 0, -1e-5), Vec<3>(0, 1e-5, 0)})
    EXPECT_LT(cantilever_error<3>(m, k, E, nu, 1.0, force), 0.05) << "load " << force.transpose();
}

TEST(FittedSprings, StopEarlyByDefaultOnlyWhereAStepCostsSeconds) {
  // The default patience (kAutoPatience): run to the tolerance below kEarlyStopDofs free dofs
  // (Cook's membrane, the strips, the 500-node blocks: where the held-out modes are too coarse
  // to stop on), stop at the first step that improves neither the held-out error nor the
  // objective by 15 % above it. A clamped 241 x 33 strip (15,840 free dofs): the default fit is
  // the patience-1 fit, bit for bit, in fewer steps than the fit to tolerance.
  const FitOptions defaults;
  EXPECT_EQ(defaults.patience_for(FitOptions::kEarlyStopDofs), 0);
  EXPECT_EQ(defaults.patience_for(FitOptions::kEarlyStopDofs + 1), 1);
  FitOptions explicit_zero;
  explicit_zero.patience = 0;
  EXPECT_EQ(explicit_zero.patience_for(100000), 0) << "an explicit patience is kept";
  const Mesh2 m = generate_rectangle({0.6, 0.08}, {240, 32});
  FitOptions o;
  o.supports = m.groups.at("left").nodes;
  std::sort(o.supports.begin(), o.supports.end());
  ASSERT_GT(2 * (m.num_nodes() - static_cast<int>(o.supports.size())), FitOptions::kEarlyStopDofs);
  FitOptions one = o, zero = o;
  one.patience = 1;
  zero.patience = 0;
  FitReport rep, rep_one, rep_zero;
  const Eigen::VectorXd k = fitted_stiffness(m, 1.0, 0.3, 1.0, o, &rep);
  EXPECT_EQ(k, fitted_stiffness(m, 1.0, 0.3, 1.0, one, &rep_one));
  fitted_stiffness(m, 1.0, 0.3, 1.0, zero, &rep_zero);
  std::cout << "steps: default " << rep.iterations << ", to tolerance " << rep_zero.iterations << "; held-out "
            << rep.validation() << " vs " << rep_zero.validation() << "\n";
  EXPECT_LT(rep.iterations, rep_zero.iterations);
}

#ifdef VTB_HAVE_CGAL_MESHERS // the block comes from CGAL Mesh_3 (VTB_WITH_CGAL=OFF skips it)
/// The clamped block's static answer, springs against P1: `bottom` clamped, `load` spread over
/// `top`, relative L2 error over all nodes.
double block_error(const Mesh3& m, const Eigen::VectorXd& k, double E, double nu, const std::vector<bool>& fixed,
                   const Eigen::VectorXd& f) {
  return test::static_error(m, k, nullptr, E, nu, 1.0, fixed, f);
}

/// Two strips of the block's top face (x <= 1 cm, x >= 3 cm) under opposite uniform tractions
/// along y, lumped onto the vertices of the facets inside each strip by a third of their area.
Eigen::VectorXd strip_traction(const Mesh3& m) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * m.num_nodes());
  for (const auto& facet : boundary_facets(m)) {
    bool top = true, low = true, high = true;
    for (int v : facet) {
      top = top && m.points(2, v) > 0.04 - 1e-9;
      low = low && m.points(0, v) <= 0.01 + 1e-9;
      high = high && m.points(0, v) >= 0.03 - 1e-9;
    }
    if (!top || !(low || high)) continue;
    const Eigen::Vector3d a = m.points.col(facet[0]), b = m.points.col(facet[1]), c = m.points.col(facet[2]);
    const double share = 0.5 * (b - a).cross(c - a).norm() / 3.0;
    for (int v : facet) f[3 * v + 1] += low ? share : -share;
  }
  return f;
}

TEST(FittedSprings, TrainOnTheScenesSupportsAndBeatLloydOnAClampedBlock) {
  // A held-out case: a CGAL Mesh_3 block clamped at its bottom, its top sheared,
  // pressed and twisted, nu 0.3 (off the Cauchy value, so no network is exact). The free-body
  // fit was worse than Lloyd here; trained on the clamped body's modes (the scene's supports)
  // the fitted network is held to the 5 % goal on each load and to half Lloyd's error.
  // No load below is in the training set: it sees the lowest clamped modes and the uniform
  // stress states' tractions on the whole boundary, not these patches. The tolerance is the
  // issue's 5 % goal (a P1 mesh of this size is itself a few percent from the continuum, so
  // closer is not asked of springs).
  const Mesh3 m = mesh_box({0.04, 0.04, 0.04}, 500);
  const double E = 5.0e4, nu = 0.3;
  std::vector<bool> fixed(static_cast<std::size_t>(m.num_nodes()), false);
  for (int v : m.groups.at("bottom").nodes) fixed[static_cast<std::size_t>(v)] = true;
  FitOptions o;
  o.supports = m.groups.at("bottom").nodes;
  std::sort(o.supports.begin(), o.supports.end());
  FitReport rep;
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, 1.0, o, &rep);
  const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, 1.0);
  EXPECT_EQ(rep.chosen, "fitted") << "the guard keeps the fit where it validates better";
  const std::vector<int>& top = m.groups.at("top").nodes;
  const auto load = [&](auto&& per_node) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * m.num_nodes());
    for (int v : top) f.segment<3>(3 * v) = per_node(m.points.col(v));
    return f;
  };
  const Eigen::Vector3d centre(0.02, 0.02, 0.04);
  const std::pair<const char*, Eigen::VectorXd> loads[] = {
      {"shear", load([](const Eigen::Vector3d&) { return Eigen::Vector3d(1e-3, 0, 0); })},
      {"press", load([](const Eigen::Vector3d&) { return Eigen::Vector3d(0, 0, -1e-3); })},
      {"twist", load([&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
         const Eigen::Vector3d r = x - centre;
         return 0.05 * Eigen::Vector3d(-r.y(), r.x(), 0);
       })},
      // fidelity.csv's twist: the top's strips x <= 1 cm and x >= 3 cm pushed along +y and -y
      // by a uniform traction lumped by area, as a scene's box load is; the load's edges cut
      // across the face (7.1 % before the training answers were weighted by energy,
      // FitOptions::weighting).
      {"strips", strip_traction(m)}};
  for (const auto& [name, f] : loads) {
    const double fitted = block_error(m, k, E, nu, fixed, f), before = block_error(m, lloyd, E, nu, fixed, f);
    EXPECT_LT(fitted, 0.05) << name << ", lloyd " << before;
    EXPECT_LT(fitted, 0.5 * before) << name;
    std::cout << name << ": lloyd " << before << ", fitted " << fitted << "\n";
  }
}
#endif

#ifdef VTB_HAVE_CGAL_MESHERS
TEST(FittedSprings, HoldAPlateWithAHoleInTensionAndShearFromNuPointTwoToPointFourFive) {
  // Issue 25's plate with a hole: a CGAL plate of 10 x 5 cm with a central hole of radius
  // 1.2 cm (Kirsch's problem: the hoop stress at the rim is 3x the far field in tension),
  // clamped on its left edge, its right edge pulled (tension) or sheared. The fit trains on
  // the clamped plate's modes and uniform stress states; the rim's stress concentration is in
  // neither. Held to the goal of 5 % and to never worse than Lloyd.
  const Mesh2 m = mesh_rectangle({0.1, 0.05}, 600, 0.012);
  const double E = 5.0e4, t = 0.001;
  std::vector<bool> fixed(static_cast<std::size_t>(m.num_nodes()), false);
  for (int v : m.groups.at("left").nodes) fixed[static_cast<std::size_t>(v)] = true;
  for (const double nu : {0.2, 0.3, 0.45}) {
    FitOptions o;
    o.supports = m.groups.at("left").nodes;
    std::sort(o.supports.begin(), o.supports.end());
    FitReport rep;
    const Eigen::VectorXd k = fitted_stiffness(m, E, nu, t, o, &rep);
    const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, t);
    for (const Vec<2>& force : {Vec<2>(1e-4, 0), Vec<2>(0, 1e-5)}) {
      Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * m.num_nodes());
      for (int v : m.groups.at("right").nodes) f.segment<2>(2 * v) = force;
      const Eigen::VectorXd ufem = clamped_solve(fem_stiffness_matrix(m, E, nu, t), f, fixed, 2);
      const double fitted = (clamped_solve(spring_matrix(m, k), f, fixed, 2) - ufem).norm() / ufem.norm();
      const double before = (clamped_solve(spring_matrix(m, lloyd), f, fixed, 2) - ufem).norm() / ufem.norm();
      std::cout << "nu " << nu << " load " << force.transpose() << ": lloyd " << before << ", fitted " << fitted << " ("
                << rep.chosen << ", held-out " << rep.validation() << ")\n";
      EXPECT_LT(fitted, 0.05) << "nu " << nu << " load " << force.transpose() << ", lloyd " << before;
      EXPECT_LE(fitted, before) << "nu " << nu << " load " << force.transpose();
    }
  }
}
#endif

TEST(FittedSprings, TrainOnTheScenesSupportsAndHoldAClampedStripInTensionAndBending) {
  // Issue #25's first case: the union-jack strip clamped at its left end, where Lloyd is 23 %
  // off in tension (lattice theory: 1.305x too stiff) and 17 % in bending. Trained on the
  // clamped strip's modes alone the fit reached only 10 % in tension (a clamped strip's first
  // stretching mode is its third, at 240 times the first eigenvalue); with the uniform stress
  // answers in the training set it is held to the 5 % goal on both loads.
  const Mesh2 m = generate_rectangle({0.2, 0.02}, {40, 4});
  const double E = 5.0e4, nu = 1.0 / 3.0, t = 0.001;
  FitOptions o;
  o.supports = m.groups.at("left").nodes;
  std::sort(o.supports.begin(), o.supports.end());
  const Eigen::VectorXd k = fitted_stiffness(m, E, nu, t, o);
  const Eigen::VectorXd lloyd = lloyd_stiffness(m, E, nu, t);
  for (const Vec<2>& force : {Vec<2>(1e-4, 0), Vec<2>(0, 1e-6)}) {
    const double fitted = cantilever_error<2>(m, k, E, nu, t, force);
    const double before = cantilever_error<2>(m, lloyd, E, nu, t, force);
    EXPECT_LT(fitted, 0.05) << "load " << force.transpose() << ", lloyd " << before;
    EXPECT_LT(fitted, 0.5 * before) << "load " << force.transpose();
    std::cout << "load " << force.transpose() << ": lloyd " << before << ", fitted " << fitted << "\n";
  }
}

TEST(FittedSprings, HoldTheClampedStripWithinFivePercentFromNuPointTwoToPointFourFive) {
  // Issue 25's Poisson-ratio family, off the lattice's own 1/3 in 2D: the clamped union-jack
  // strip in tension at nu 0.2 and 0.45 (fidelity.csv: Lloyd 17.8 / 29.7 %, fitted 0.75 /
  // 4.7 %). Held to the goal of 5 % and to less than half of Lloyd's error.
  const Mesh2 m = generate_rectangle({0.2, 0.02}, {40, 4});
  const double E = 5.0e4, t = 0.001;
  for (const double nu : {0.2, 0.45}) {
    FitOptions o;
    o.supports = m.groups.at("left").nodes;
    std::sort(o.supports.begin(), o.supports.end());
    const double fitted = cantilever_error<2>(m, fitted_stiffness(m, E, nu, t, o), E, nu, t, Vec<2>(1e-4, 0));
    const double lloyd = cantilever_error<2>(m, lloyd_stiffness(m, E, nu, t), E, nu, t, Vec<2>(1e-4, 0));
    EXPECT_LT(fitted, 0.05) << "nu " << nu << ", lloyd " << lloyd;
    EXPECT_LT(fitted, 0.5 * lloyd) << "nu " << nu;
    std::cout << "nu " << nu << ": lloyd " << lloyd << ", fitted " << fitted << "\n";
  }
}

#ifdef VTB_HAVE_CGAL_MESHERS
TEST(FittedSprings, HoldTheClampedBlockInShearWithinFivePercentFromNuPointTwoToPointFourFive) {
  // The same family in 3D, off the lattice's 1/4: the CGAL block clamped at its bottom, its top
  // sheared, nu 0.2 and 0.45 (fidelity.csv, tractions lumped by area: Lloyd 12.1 / 62.1 %,
  // fitted 2.0 / 4.2 %; these equal nodal forces: 12.6 / 61.9 % and 2.2 / 4.5 %; at 0.45
  // Lloyd's springs are 2.6x too stiff). Held to 5 % and to half of Lloyd's error.
  const Mesh3 m = mesh_box({0.04, 0.04, 0.04}, 500);
  const double E = 5.0e4;
  std::vector<bool> fixed(static_cast<std::size_t>(m.num_nodes()), false);
  for (int v : m.groups.at("bottom").nodes) fixed[static_cast<std::size_t>(v)] = true;
  Eigen::VectorXd shear = Eigen::VectorXd::Zero(3 * m.num_nodes());
  for (int v : m.groups.at("top").nodes) shear[3 * v] = 1e-3;
  for (const double nu : {0.2, 0.45}) {
    FitOptions o;
    o.supports = m.groups.at("bottom").nodes;
    std::sort(o.supports.begin(), o.supports.end());
    const double fitted = block_error(m, fitted_stiffness(m, E, nu, 1.0, o), E, nu, fixed, shear);
    const double lloyd = block_error(m, lloyd_stiffness(m, E, nu, 1.0), E, nu, fixed, shear);
    EXPECT_LT(fitted, 0.05) << "nu " << nu << ", lloyd " << lloyd;
    EXPECT_LT(fitted, 0.5 * lloyd) << "nu " << nu;
    std::cout << "nu " << nu << ": lloyd " << lloyd << ", fitted " << fitted << "\n";
  }
}
#endif

TEST(FittedSprings, AreCachedPerMeshPoissonRatioAndSupports) {
  // The first fit writes the cache, a second call on the same mesh and material reads the same
  // constants back; another stiffness reads them scaled, another Poisson ratio or other
  // supports miss; a damaged file, or one another version of the fit wrote, is refitted and
  // replaced; an empty VTB_CACHE_DIR turns the cache off.
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  const Mesh2 m = generate_rectangle({0.1, 0.02}, {10, 2});
  CachedFit info;
  info.hit = true;
  const Eigen::VectorXd a = cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info);
  EXPECT_FALSE(info.hit);
  // The fit runs at unit E t and is scaled (every stiffness in it scales with E t, its
  // displacements do not): the direct fit at E t = 100 is the cached one, bit for bit.
  FitReport rep;
  EXPECT_EQ(fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &rep), a);
  EXPECT_EQ(cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info), a);
  EXPECT_TRUE(info.hit);
  EXPECT_EQ(info.chosen, rep.chosen) << "the cache keeps what the guard chose";
  EXPECT_EQ(info.validation, rep.validation()) << "and its validation error";
  EXPECT_TRUE(cached_fitted_stiffness(m, 2.0e4, 0.3, 0.01, {}, &info).isApprox(2 * a, 1e-14));
  EXPECT_TRUE(info.hit) << "another stiffness reads the same fit, scaled";
  cached_fitted_stiffness(m, 1.0e4, 0.25, 0.01, {}, &info);
  EXPECT_FALSE(info.hit) << "another Poisson ratio";
  const std::vector<int> left = m.groups.at("left").nodes;
  const Eigen::VectorXd clamped = cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, left, &info);
  EXPECT_FALSE(info.hit) << "other supports";
  EXPECT_NE(clamped, a) << "the supported body's modes train other springs";
  for (const auto& f : std::filesystem::directory_iterator(dir.path())) std::filesystem::resize_file(f.path(), 20);
  EXPECT_EQ(cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info), a);
  EXPECT_FALSE(info.hit) << "a damaged file is refitted";
  EXPECT_EQ(cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info), a);
  EXPECT_TRUE(info.hit) << "and replaced";
  // A fit cached by another version of the fit's code (its hash after the 8-byte magic).
  const std::string version = fit_code_version();
  ASSERT_EQ(version.size(), 64u);
  EXPECT_EQ(version.find_first_not_of("0123456789abcdef"), std::string::npos) << version;
  for (const auto& f : std::filesystem::directory_iterator(dir.path())) {
    std::fstream io(f.path(), std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(8);
    io.write(std::string(64, '0').c_str(), 64);
  }
  EXPECT_EQ(cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info), a);
  EXPECT_FALSE(info.hit) << "a fit cached by another version of the fit's code is refitted";
  EXPECT_EQ(cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info), a);
  EXPECT_TRUE(info.hit) << "and replaced";
  ::setenv("VTB_CACHE_DIR", "", 1);
  EXPECT_TRUE(fit_cache_dir().empty());
  cached_fitted_stiffness(m, 1.0e4, 0.3, 0.01, {}, &info);
  EXPECT_FALSE(info.hit);
  ::unsetenv("VTB_CACHE_DIR");
}

TEST(FittedSprings, AreTheDefaultWithinAutosBudgetAndLloydBeyondIt) {
  // springs = "auto" (the scene's default): a mesh the fit can afford is fitted (or keeps the
  // prior the guard chose, reported with its validation error); one too small to fit, or
  // beyond the 3D budget, runs on Lloyd's springs with a one-line note saying why.
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  EXPECT_EQ(SolverDesc{}.springs, "auto");
  MaterialDesc mat;
  mat.young_modulus = 5.0e4;
  mat.poisson_ratio = 0.3;
  mat.thickness = 0.001;
  const Mesh2 strip = generate_rectangle({0.2, 0.02}, {40, 4});
  const SpringNetwork<2> fitted = build_network(strip, mat, "auto", strip.groups.at("left").nodes);
  EXPECT_EQ(fitted.calibration_requested, "auto");
  EXPECT_EQ(fitted.calibration, "fitted");
  EXPECT_TRUE(std::isfinite(fitted.calibration_validation));
  EXPECT_TRUE(fitted.calibration_note.empty()) << fitted.calibration_note;
  const SpringNetwork<2> tiny = build_network(generate_rectangle({0.1, 0.02}, {2, 1}), mat, "auto");
  EXPECT_EQ(tiny.calibration, "lloyd");
  EXPECT_NE(tiny.calibration_note.find("too small to fit (6 nodes)"), std::string::npos) << tiny.calibration_note;
  const Mesh3 big = generate_box({0.4, 0.1, 0.1}, {80, 26, 26}); // 59,049 nodes
  ASSERT_GT(big.num_nodes(), kAutoFitNodes3D);
  const SpringNetwork<3> beyond = build_network(big, mat, "auto");
  EXPECT_EQ(beyond.calibration, "lloyd");
  EXPECT_NE(beyond.calibration_note.find("beyond auto's budget"), std::string::npos) << beyond.calibration_note;
  EXPECT_EQ(beyond.stiffness, lloyd_stiffness(big, mat.young_modulus, mat.poisson_ratio, 1.0));
  ::unsetenv("VTB_CACHE_DIR");
}

/// A scene on `mesh` with the given springs and Poisson ratio: its bottom row of nodes (y <= 0.1)
/// fixed and `load` (TOML) appended.
Model<2> patch_model(const Mesh2& mesh, const char* springs, double nu, const std::string& load) {
  std::ostringstream nu_text; // all digits: at nu = 1/3 Lloyd's element is the P1 element
  nu_text << std::setprecision(17) << nu;
  const Scene s = parse_scene("[scene]\nname = \"patch\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\n"
                              "generate = { shape = \"rectangle\", size = [1.0, 1.0], divisions = [1, 1] }\n"
                              "[material]\nyoung_modulus = 1.0e4\npoisson_ratio = " +
                                  nu_text.str() + "\ndensity = 1000.0\nthickness = 0.01\n[solver]\nsprings = \"" +
                                  springs + "\"\n[[fix]]\nbox = [[-1.0, -1.0], [100.0, 0.1]]\n" + load,
                              "patch.toml", ".");
  return build_model<2>(s, mesh);
}

TEST(LoadCheck, MeasuresTheSpringsAgainstTheFemOnTheScenesOwnLoads) {
  // Every run's check of its springs (load_check.hh): the springs' linear static answer to the
  // scene's loads against the P1 FEM's. Equilateral triangles at nu = 1/3: Lloyd's element is
  // the P1 element, so the two answers agree to rounding (the factorisations' relative error,
  // 1e-12 on this 117-node patch). At nu = 0.2 no network is exact: the check must equal the
  // error of this file's own clamped solves (Eigen's LDL^T, another restriction to the free
  // dofs) to their rounding, and the fit must bring it down.
  const Mesh2 m = equilateral_patch(12, 8);
  const double top = m.points.row(1).maxCoeff();
  const std::string pull = "[[load]]\nbox = [[-1.0, " + std::to_string(top - 0.01) + "], [100.0, " +
                           std::to_string(top + 0.01) + "]]\ntotal_force = [1.0, 0.5]\n";
  const Model<2> exact = patch_model(m, "lloyd", 1.0 / 3.0, pull);
  EXPECT_LT(exact.net.calibration_load_error, 1e-9);
  const Model<2> lloyd = patch_model(m, "lloyd", 0.2, pull);
  std::vector<bool> fixed(static_cast<std::size_t>(m.num_nodes()));
  Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * m.num_nodes());
  for (int v = 0; v < m.num_nodes(); ++v)
    fixed[static_cast<std::size_t>(v)] = lloyd.constrained[static_cast<std::size_t>(v)];
  Nodal<2> loads(2, m.num_nodes());
  lloyd.external_forces(1e9, loads); // every load at its full value
  for (int v = 0; v < m.num_nodes(); ++v) f.segment<2>(2 * v) = loads.col(v);
  const Eigen::VectorXd ufem = clamped_solve(fem_stiffness_matrix(m, 1.0e4, 0.2, 0.01), f, fixed, 2);
  const Eigen::VectorXd us = clamped_solve(spring_matrix(m, lloyd.net.stiffness), f, fixed, 2);
  const double expected = (us - ufem).norm() / ufem.norm();
  EXPECT_GT(expected, 0.01) << "off the Cauchy value no network is exact";
  EXPECT_NEAR(lloyd.net.calibration_load_error, expected, 1e-9 * expected);
  EXPECT_LT(patch_model(m, "fitted", 0.2, pull).net.calibration_load_error, lloyd.net.calibration_load_error);
  // Not measured (NaN, and summary.json leaves it out): no load, or a body its supports do not
  // hold (a free body under loads has no static answer).
  EXPECT_TRUE(std::isnan(patch_model(m, "lloyd", 0.2, "").net.calibration_load_error));
  const Scene free = parse_scene("[scene]\nname = \"free\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\n"
                                 "generate = { shape = \"rectangle\", size = [1.0, 1.0], divisions = [1, 1] }\n"
                                 "[material]\nyoung_modulus = 1.0e4\npoisson_ratio = 0.2\ndensity = 1000.0\n" +
                                     pull,
                                 "free.toml", ".");
  EXPECT_TRUE(std::isnan(build_model<2>(free, m).net.calibration_load_error));
}

TEST(FittedSprings, RefuseAMeshTooSmallToFitWithOneLine) {
  // 6 nodes (12 dofs, 3 rigid) cannot hold 16 training modes and their Ritz guard: bad input
  // naming the key, not an internal error.
  try {
    fitted_stiffness(generate_rectangle({0.1, 0.02}, {2, 1}), 1.0e4, 0.3, 0.01);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("[solver].springs = \"fitted\": the mesh has 6 nodes"), std::string::npos)
        << e.what();
  }
}

TEST(FittedSprings, AreDeterministic) {
  const Mesh2 m = generate_rectangle({0.1, 0.02}, {10, 2});
  const Eigen::VectorXd a = fitted_stiffness(m, 1.0e4, 0.3, 0.01);
  const Eigen::VectorXd b = fitted_stiffness(m, 1.0e4, 0.3, 0.01);
  EXPECT_EQ(a, b);
}

} // namespace
} // namespace vtb
