// The volume term averaged per node (cell_volumes.hh, `springs = "nodal-volume"`): its force is
// minus its energy's gradient (2D and 3D, through inversion, with the stable shear part too);
// the exact Jacobian (with the stars' coupling) is the force's derivative; the per-cell bound the
// integrators take dominates it; a homogeneous J costs what the per-cell term charges; and one
// constraint per node leaves the isochoric motions free where one per cell holds every motion.
//
// Tolerances: central differences with step h of a polynomial energy (degree 2 dim in the
// nodes) have truncation error ~ h^2 |E'''| and round-off ~ eps E / h, both below 1e-7 of the
// largest force (or stiffness) at h = 1e-6 of the mesh size; a dropped term or a wrong weight is
// O(1) of it. Null spaces: the free stiffness's eigenvalues at or below 1e-9 of the largest
// (round-off of a 150-dof assembly is ~ 1e-14 of it, the smallest non-zero ~ 1e-3).
#include "support/central_differences.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/springs/cell_volumes.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <random>

namespace vtb {
namespace {

template <int dim> Mesh<dim> small_mesh() {
  if constexpr (dim == 2)
    return generate_rectangle(Eigen::Vector2d(1.0, 1.0), Eigen::Vector2i(3, 3));
  else
    return generate_box(Eigen::Vector3d(1.0, 1.0, 1.0), Eigen::Vector3i(2, 2, 2));
}

/// The cells' term alone with random constants k_c in [0.5, 1.5], averaged per node.
template <int dim> CellVolumes<dim> nodal_cells(const Mesh<dim>& m, bool shear, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(0.5, 1.5);
  Eigen::VectorXd k(m.num_cells());
  for (Eigen::Index c = 0; c < k.size(); ++c) k[c] = r(gen);
  CellVolumes<dim> cv = make_cell_volumes<dim>(m.cells, m.points, k, 0.0);
  if (shear) set_cell_shear(cv, 1.0, 0.5, 1.0, 0.0);
  make_nodal_volumes(cv, m.num_nodes());
  return cv;
}

template <int dim> void check_force_is_minus_the_gradient(bool shear, unsigned seed) {
  const Mesh<dim> m = small_mesh<dim>();
  const CellVolumes<dim> cv = nodal_cells(m, shear, seed);
  ASSERT_TRUE(cv.nodal());
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-0.25, 0.25); // cells 0.33-0.5 wide: some invert
  int inverted = 0;
  const Nodal<dim> v = Nodal<dim>::Zero(dim, m.num_nodes());
  for (int trial = 0; trial < 6; ++trial) {
    Nodal<dim> u(dim, m.num_nodes());
    for (Eigen::Index k = 0; k < u.size(); ++k) u.data()[k] = r(gen);
    inverted += volume_ratios<dim>(m.cells, m.points, u).inverted;
    Nodal<dim> f = Nodal<dim>::Zero(dim, m.num_nodes());
    add_volume_forces(cv, m.points, u, v, f, 0.0);
    const Nodal<dim> fd = test::minus_energy_gradient(cv, m.points, u, 1e-6);
    EXPECT_LT((f - fd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, f.cwiseAbs().maxCoeff())) << "trial " << trial;
    EXPECT_LT(f.rowwise().sum().norm(), 1e-12 * std::max(1.0, f.cwiseAbs().maxCoeff())); // no net force
  }
  EXPECT_GT(inverted, 0) << "some trials pass through inversion";
}

TEST(NodalVolumes, ForceIsMinusTheEnergysGradientThroughInversion2D) {
  check_force_is_minus_the_gradient<2>(false, 5);
}
TEST(NodalVolumes, ForceIsMinusTheEnergysGradientThroughInversion3D) {
  check_force_is_minus_the_gradient<3>(false, 6);
}
TEST(NodalVolumes, WithTheStableShearTheForceIsStillTheGradient3D) {
  check_force_is_minus_the_gradient<3>(true, 7);
}

/// The network with its springs' constants zeroed: the volume term alone, through the
/// production path (build_network), no dashpots.
template <int dim> SpringNetwork<dim> volume_only(const Mesh<dim>& m, const char* calibration) {
  SpringNetwork<dim> net = build_network(m, MaterialDesc{1.0, 0.45, 1000.0, 1.0, 0.0, 0.0}, calibration);
  net.stiffness.setZero();
  net.damping.setZero();
  return net;
}

template <int dim> void check_exact_jacobian(unsigned seed) {
  const Mesh<dim> m = small_mesh<dim>();
  const SpringNetwork<dim> net = build_network(m, MaterialDesc{1.0, 0.45, 1000.0, 1.0, 0.0, 0.0}, "nodal-volume");
  ASSERT_TRUE(net.volume.nodal());
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-0.1, 0.1);
  Nodal<dim> u(dim, m.num_nodes());
  for (Eigen::Index k = 0; k < u.size(); ++k) u.data()[k] = r(gen);
  const Eigen::MatrixXd K(force_jacobians(net, u, false).K);
  const Nodal<dim> v = Nodal<dim>::Zero(dim, m.num_nodes());
  const double h = 1e-6;
  Eigen::MatrixXd fd(K.rows(), K.cols());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    Nodal<dim> up = u, um = u, fp = Nodal<dim>::Zero(dim, m.num_nodes()), fm = fp;
    up.data()[k] += h;
    um.data()[k] -= h;
    add_internal_forces(net, up, v, fp);
    add_internal_forces(net, um, v, fm);
    const Nodal<dim> df = fp - fm;
    fd.col(k) = Eigen::Map<const Eigen::VectorXd>(df.data(), df.size()) / (2 * h);
  }
  EXPECT_LT((K - fd).cwiseAbs().maxCoeff(), 1e-7 * K.cwiseAbs().maxCoeff());
  // The stars' coupling is there: some node pair that shares no cell has a non-zero block.
  const Eigen::MatrixXd bound(force_jacobians(net, u, true).K);
  EXPECT_GT((K - bound).cwiseAbs().maxCoeff(), 1e-3 * K.cwiseAbs().maxCoeff());
}

TEST(NodalVolumes, TheExactJacobianIsTheForcesDerivative2D) {
  check_exact_jacobian<2>(8);
}
TEST(NodalVolumes, TheExactJacobianIsTheForcesDerivative3D) {
  check_exact_jacobian<3>(9);
}

/// At rest -K_bound + K_exact is positive semidefinite (Jensen: g_n g_n^T <= sum_c w_cn g_c g_c^T),
/// so an implicit step or a filter that takes the bound is stiffer than the term, never softer.
template <int dim> void check_bound_dominates() {
  const Mesh<dim> m = small_mesh<dim>();
  const SpringNetwork<dim> net = volume_only(m, "nodal-volume");
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, m.num_nodes());
  const Eigen::MatrixXd exact(-force_jacobians(net, rest, false).K), bound(-force_jacobians(net, rest, true).K);
  const Eigen::VectorXd gap = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(bound - exact).eigenvalues();
  const double scale = bound.cwiseAbs().maxCoeff();
  EXPECT_GT(gap.minCoeff(), -1e-12 * scale);
  EXPECT_GT(gap.maxCoeff(), 1e-3 * scale); // and strictly stiffer somewhere
}

TEST(NodalVolumes, TheBoundTheIntegratorsTakeDominatesTheTerm2D) {
  check_bound_dominates<2>();
}
TEST(NodalVolumes, TheBoundTheIntegratorsTakeDominatesTheTerm3D) {
  check_bound_dominates<3>();
}

TEST(NodalVolumes, AHomogeneousVolumeChangeCostsWhatThePerCellTermCharges) {
  // Every cell's J is det(I + A) under u = A X, so every node's mean is too, and the nodes'
  // constants (a (dim + 1)-th of each of their cells') sum to the cells'.
  const Mesh<3> m = small_mesh<3>();
  const SpringNetwork<3> cells = volume_only(m, "volume"), nodes = volume_only(m, "nodal-volume");
  Mat<3> A;
  A << -0.2, 0.05, 0.0, 0.02, -0.1, 0.03, 0.0, 0.01, 0.15;
  const Nodal<3> u = A * m.points;
  const double e_cells = volume_energy(cells.volume, m.points, u);
  ASSERT_GT(e_cells, 0.0);
  EXPECT_NEAR(volume_energy(nodes.volume, m.points, u), e_cells, 1e-12 * e_cells);
}

/// The isochoric motions a clamped block keeps: the null space of the volume term's rest
/// stiffness on the free dofs. Each cell's volume is a constraint, and a tetrahedral mesh has
/// five to six cells a node against three dofs, so per cell hardly any free motion keeps every
/// volume (here only near the top face's rim, whose 12 nodes have one to three cells): nearly
/// incompressible, the block locks. Per node there is one constraint a node, and at least
/// 3 nf - nodes isochoric motions remain, as a nearly incompressible solid has.
TEST(NodalVolumes, OneConstraintPerNodeLeavesTheIsochoricMotionsFree3D) {
  constexpr int dim = 3;
  // Its free nodes moved at random by up to a fifth of a cell: a Kuhn lattice's volumes are
  // not independent (its cubes' six cells admit isochoric fields), a mesher's are.
  Mesh<dim> m = generate_box(Eigen::Vector3d(1.0, 1.0, 1.0), Eigen::Vector3i(3, 3, 3));
  std::mt19937 gen(10);
  std::uniform_real_distribution<double> jitter(-1.0 / 15, 1.0 / 15);
  for (int i = 0; i < m.num_nodes(); ++i)
    if (m.points(dim - 1, i) > 1e-9)
      for (int p = 0; p < dim; ++p) m.points(p, i) += jitter(gen);
  std::vector<int> free_index(static_cast<std::size_t>(m.num_nodes()), -1);
  int nf = 0;
  for (int i = 0; i < m.num_nodes(); ++i)
    if (m.points(dim - 1, i) > 1e-9) free_index[static_cast<std::size_t>(i)] = nf++; // clamped at z = 0
  const auto isochoric = [&](const char* calibration) {
    const SpringNetwork<dim> net = volume_only(m, calibration);
    const Nodal<dim> rest = Nodal<dim>::Zero(dim, m.num_nodes());
    const Eigen::MatrixXd K(free_stiffness(net, rest, free_index, nf, false));
    const Eigen::VectorXd e = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues();
    return static_cast<int>((e.array() <= 1e-9 * e.maxCoeff()).count());
  };
  EXPECT_LE(isochoric("volume"), 12) << "per cell: a motion keeps every volume only at the rim";
  EXPECT_GE(isochoric("nodal-volume"), dim * nf - m.num_nodes()) << "per node: one constraint a node";
}

} // namespace
} // namespace vtb
