// Finite-difference checks of the assembled Jacobians (docs/testing.md: every force and
// Jacobian): the reference assembly force_jacobians against add_internal_forces, CVODE's
// analytic Jacobian against differences of its right-hand side (with supports, ramped drives
// and mass damping), and implicit Euler's step against a dense solve of the backward-Euler
// system built from the reference assembly. A Newton iteration converges with a wrong
// Jacobian, so accuracy tests of the trajectories cannot find one; these can.
//
// Tolerances: central differences with step h have truncation error ~ h^2 |f'''| and round-off
// ~ eps |f| / h. With h = 1e-6 x the mesh size on strains of 0.1, the truncation part is
// ~ 1e-12 of the stiffness and the round-off ~ eps x 0.1 / 1e-6 ~ 2e-11 of it; 1e-7 of the
// largest entry bounds both with margin, while a sign error or a dropped term is O(1) of it.
#include "support/small_models.hh"
#include "vtb/linalg/block_solve.hh"
#include "vtb/solvers/cvode_solver.hh"
#include "vtb/solvers/implicit_euler.hh"
#include "vtb/solvers/tensor_filter.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/load_check.hh"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

namespace vtb {
namespace {

constexpr double kTol = 1e-7;

const char* kPlate2 = R"(
[scene]
duration = 1.0
output_interval = 0.1
[mesh]
generate = { shape = "rectangle", size = [0.2, 0.05], divisions = [4, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.3333
density = 1000.0
thickness = 0.001
retardation_time = 0.05
mass_damping = 3.0
[[fix]]
group = "left"
[[drive]]
point = [0.2, 0.05]
displacement = [0.004, -0.006]
start = 0.1
ramp = 0.5
[[load]]
group = "right"
total_force = [0.1, -0.05]
start = 0.0
ramp = 0.3
)";

const char* kBox3 = R"(
[scene]
duration = 1.0
output_interval = 0.1
[mesh]
generate = { shape = "box", size = [0.1, 0.04, 0.03], divisions = [3, 2, 1] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.25
density = 1000.0
retardation_time = 0.02
mass_damping = 2.0
[[fix]]
group = "left"
[[drive]]
point = [0.1, 0.04, 0.03]
displacement = [0.002, -0.003, 0.001]
start = 0.1
ramp = 0.5
[[load]]
group = "right"
total_force = [0.0, -0.01, 0.005]
ramp = 0.3
)";

template <int dim> Model<dim> model_of(const char* text) {
  const Scene s = parse_scene(text, "jac.toml", ".");
  return build_model<dim>(s, std::get<Mesh<dim>>(load_mesh(s)));
}

/// The same scene with the volume term per cell (springs = "volume") and nu = 0.45, where the
/// term carries most of lambda (cell_volumes.hh).
template <int dim> Model<dim> volume_model_of(const char* text) {
  std::string t(text);
  const auto at = t.find("poisson_ratio = ");
  t.replace(at, t.find('\n', at) - at, "poisson_ratio = 0.45");
  t += "[solver]\nsprings = \"volume\"\n";
  Model<dim> m = model_of<dim>(t.c_str());
  EXPECT_EQ(m.net.volume.size(), m.mesh.num_cells());
  EXPECT_GT(m.net.volume.stiffness.minCoeff(), 0.0);
  return m;
}

/// A deformed state: every node displaced by up to 15 % of the mesh size (springs both
/// stretched and compressed), velocities of order 1 mesh size per second.
template <int dim> State<dim> random_state(const Model<dim>& model, double vscale, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-1.0, 1.0);
  const double h = model.net.rest_length.minCoeff();
  State<dim> s = initial_state(model);
  for (int i = 0; i < model.num_nodes(); ++i)
    for (int p = 0; p < dim; ++p) {
      s.u(p, i) = 0.15 * h * r(gen);
      s.v(p, i) = vscale * h * r(gen);
    }
  return s;
}

template <int dim> Eigen::VectorXd forces(const Model<dim>& m, const Nodal<dim>& u, const Nodal<dim>& v) {
  Nodal<dim> f = Nodal<dim>::Zero(dim, m.num_nodes());
  add_internal_forces(m.net, u, v, f);
  return Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
}

/// `spread`: the displacements' scale in units of 15 % of the mesh size (8: up to 120 %, where
/// cells invert).
template <int dim> void check_force_jacobians(const Model<dim>& m, double spread = 1.0) {
  // K at v = 0 (the dashpot's direction term, omitted by design, vanishes there); D at any v
  // (the force is linear in v, so the difference is exact but for round-off).
  State<dim> s = random_state(m, 0.0, 7);
  State<dim> sv = random_state(m, 1.0, 7);
  s.u *= spread;
  sv.u *= spread;
  if (spread > 1 && !m.net.volume.empty()) {
    EXPECT_GT(volume_ratios<dim>(m.mesh.cells, m.net.rest, s.u).inverted, 0) << "the check passes through inversion";
  }
  const ForceJacobians<dim> J = force_jacobians(m.net, s.u, false);
  const Eigen::MatrixXd K(J.K), D(J.D);
  const double h = 1e-6 * m.net.rest_length.minCoeff();
  const int n = dim * m.num_nodes();
  Eigen::MatrixXd Kfd(n, n), Dfd(n, n);
  for (int c = 0; c < n; ++c) {
    Nodal<dim> up = s.u, um = s.u, vp = sv.v, vm = sv.v;
    up.data()[c] += h;
    um.data()[c] -= h;
    vp.data()[c] += h;
    vm.data()[c] -= h;
    Kfd.col(c) = (forces(m, up, s.v) - forces(m, um, s.v)) / (2 * h);
    Dfd.col(c) = (forces(m, sv.u, vp) - forces(m, sv.u, vm)) / (2 * h);
  }
  EXPECT_LT((K - Kfd).cwiseAbs().maxCoeff(), kTol * K.cwiseAbs().maxCoeff());
  // D is checked at the velocities' own state (its direction depends on u).
  const Eigen::MatrixXd Dv(force_jacobians(m.net, sv.u, false).D);
  EXPECT_LT((Dv - Dfd).cwiseAbs().maxCoeff(), kTol * Dv.cwiseAbs().maxCoeff());
  EXPECT_GT(D.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-12 * K.cwiseAbs().maxCoeff()) << "K is symmetric";
}

/// free_stiffness (the load check's matrix, and the fit's through fill_free_stiffness, assembled
/// on free_block_pattern without triplets) is -K of the reference assembly on the free dofs to the
/// bit: each entry sums the same springs' blocks in the same order as setFromTriplets does.
template <int dim> void check_free_stiffness(const Model<dim>& m) {
  ASSERT_LT(m.free_nodes.size(), static_cast<std::size_t>(m.num_nodes())) << "a case with held nodes";
  const State<dim> s = random_state(m, 0.0, 11);
  const int nf = static_cast<int>(m.free_nodes.size());
  for (bool clamp : {false, true}) {
    const Eigen::MatrixXd want(free_dof_block(Eigen::SparseMatrix<double>(-force_jacobians(m.net, s.u, clamp).K), m));
    const Eigen::SparseMatrix<double> got = free_stiffness(m.net, s.u, m.free_index, nf, clamp);
    EXPECT_EQ((Eigen::MatrixXd(got) - want).cwiseAbs().maxCoeff(), 0.0);
    // The pattern is the node blocks and the blocks of springs between free nodes, no more.
    long blocks = nf;
    for (const auto& e : m.net.edge)
      blocks +=
          2 * (m.free_index[static_cast<std::size_t>(e[0])] >= 0 && m.free_index[static_cast<std::size_t>(e[1])] >= 0);
    EXPECT_EQ(got.nonZeros(), blocks * dim * dim);
    // Blocks::lower (the fit's matrix): the same values to the bit where the row node is at or
    // after the column node, the diagonal blocks whole, nothing else.
    Eigen::SparseMatrix<double> lower = free_block_pattern(m.net, m.free_index, nf, Blocks::lower);
    fill_free_stiffness(m.net, s.u, m.free_index, clamp, lower, Blocks::lower);
    Eigen::MatrixXd want_lower = Eigen::MatrixXd::Zero(want.rows(), want.cols());
    for (int c = 0; c < want.cols(); ++c)
      for (int r = dim * (c / dim); r < want.rows(); ++r) want_lower(r, c) = want(r, c);
    EXPECT_EQ((Eigen::MatrixXd(lower) - want_lower).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(lower.nonZeros(), (blocks + nf) / 2 * dim * dim);
  }
}

TEST(ForceJacobians, FreeStiffnessIsTheReferenceOnTheFreeDofs2D) {
  check_free_stiffness(model_of<2>(kPlate2));
}
TEST(ForceJacobians, FreeStiffnessIsTheReferenceOnTheFreeDofs3D) {
  check_free_stiffness(model_of<3>(kBox3));
}

TEST(ForceJacobians, FreeStiffnessIsTheReferenceWithTheVolumeTerm) {
  check_free_stiffness(volume_model_of<2>(kPlate2));
  check_free_stiffness(volume_model_of<3>(kBox3));
}

// The volume term's blocks (cell_volumes.hh) by the same differences, at strains of 15 % and
// through inversion (displacements up to 120 % of the mesh size, cells with J < 0): its force is
// a polynomial of the nodes, so the tolerance's argument holds there too.
TEST(ForceJacobians, MatchForceDifferencesWithTheVolumeTerm2D) {
  const Model<2> m = volume_model_of<2>(kPlate2);
  check_force_jacobians(m);
  check_force_jacobians(m, 8.0);
}
TEST(ForceJacobians, MatchForceDifferencesWithTheVolumeTerm3D) {
  const Model<3> m = volume_model_of<3>(kBox3);
  check_force_jacobians(m);
  check_force_jacobians(m, 8.0);
}

/// The same with the stable energy's shear part in every cell (`springs = "fitted-stable"`'s
/// term, set here on the element fit's cells without a fit): its blocks, its alpha shift and its
/// dashpot, through inversion; the term's force is still a polynomial of the nodes.
/// Both scenes: E 5e4 Pa, nu 0.45 (volume_model_of); the plate 1 mm thick, tau 0.05 s; the box
/// tau 0.02 s.
template <int dim> Model<dim> stable_model_of(const char* text, double thickness, double tau) {
  Model<dim> m = volume_model_of<dim>(text);
  set_cell_shear(m.net.volume, 5.0e4 / (2 * 1.45), 0.5, thickness, tau);
  EXPECT_GT(m.net.volume.shear.minCoeff(), 0.0);
  return m;
}
TEST(ForceJacobians, MatchForceDifferencesWithTheStableShearPart) {
  const Model<2> m2 = stable_model_of<2>(kPlate2, 0.001, 0.05);
  check_force_jacobians(m2);
  check_force_jacobians(m2, 8.0);
  check_free_stiffness(m2);
  const Model<3> m3 = stable_model_of<3>(kBox3, 1.0, 0.02);
  check_force_jacobians(m3);
  check_force_jacobians(m3, 8.0);
  check_free_stiffness(m3);
}

TEST(ForceJacobians, MatchForceDifferences2D) {
  check_force_jacobians(model_of<2>(kPlate2));
}
TEST(ForceJacobians, MatchForceDifferences3D) {
  check_force_jacobians(model_of<3>(kBox3));
}

/// The tensor filter's H (tensor_filter.hh) at rest: H(0) = M (1 + dt gamma) + dt D_0 + dt^2 K_0
/// on the free dofs with K_0 = -df/du and D_0 = -df/dv at rest by central differences of
/// add_internal_forces, and H(1) - H(0) = per spring (dt c + dt^2 k)(I - n n^T) with the signs
/// of a stiffness (the transverse cover).
template <int dim> void check_tensor_filter(const Model<dim>& m) {
  const double dt = 0.01, h = 1e-6 * m.net.rest_length.minCoeff();
  const int nf = static_cast<int>(m.free_nodes.size()), n = dim * m.num_nodes();
  const Nodal<dim> zero = Nodal<dim>::Zero(dim, m.num_nodes());
  Eigen::MatrixXd K(n, n), D(n, n);
  for (int c = 0; c < n; ++c) {
    Nodal<dim> p = zero, q = zero;
    p.data()[c] += h;
    q.data()[c] -= h;
    K.col(c) = -(forces(m, p, zero) - forces(m, q, zero)) / (2 * h);
    D.col(c) = -(forces(m, zero, p) - forces(m, zero, q)) / (2 * h);
  }
  Eigen::MatrixXd expected0(dim * nf, dim * nf), transverse = Eigen::MatrixXd::Zero(dim * nf, dim * nf);
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b)
      for (int p = 0; p < dim; ++p)
        for (int q = 0; q < dim; ++q) {
          const int r = dim * m.free_nodes[static_cast<std::size_t>(a)] + p;
          const int c = dim * m.free_nodes[static_cast<std::size_t>(b)] + q;
          // D_0 holds -gamma m on its diagonal (mass damping): M (1 + dt gamma) = M + dt gamma M.
          expected0(dim * a + p, dim * b + q) = dt * D(r, c) + dt * dt * K(r, c) + (r == c ? m.net.mass[r / dim] : 0.0);
        }
  for (int s = 0; s < m.net.num_springs(); ++s) {
    const auto [i, j] = m.net.edge[static_cast<std::size_t>(s)];
    const Vec<dim> nv = (m.net.rest.col(j) - m.net.rest.col(i)).normalized();
    const Mat<dim> B =
        (dt * m.net.damping[s] + dt * dt * m.net.stiffness[s]) * (Mat<dim>::Identity() - nv * nv.transpose());
    const int a = m.free_index[static_cast<std::size_t>(i)], b = m.free_index[static_cast<std::size_t>(j)];
    if (a >= 0) transverse.template block<dim, dim>(dim * a, dim * a) += B;
    if (b >= 0) transverse.template block<dim, dim>(dim * b, dim * b) += B;
    if (a >= 0 && b >= 0) {
      transverse.template block<dim, dim>(dim * a, dim * b) -= B;
      transverse.template block<dim, dim>(dim * b, dim * a) -= B;
    }
  }
  const Eigen::MatrixXd H0(tensor_filter_matrix(m, dt, 0.0)), H1(tensor_filter_matrix(m, dt, 1.0));
  EXPECT_LT((H0 - expected0).cwiseAbs().maxCoeff(), kTol * H0.cwiseAbs().maxCoeff());
  EXPECT_LT((H1 - H0 - transverse).cwiseAbs().maxCoeff(), 1e-12 * H1.cwiseAbs().maxCoeff());
  EXPECT_GT(transverse.cwiseAbs().maxCoeff(), 1e-3 * H0.cwiseAbs().maxCoeff());
}

/// The tensor filter relinearised at a stretched and sheared shape u: its H is M (1 + dt gamma)
/// + dt D(u) + dt^2 K(u) from the reference assembly force_jacobians (K's transverse term
/// clamped under compression, as implicit Euler's), the mismatch measured from that shape is
/// 0, and relinearising at rest again gives back the H it was built with. Both sides sum the
/// same spring blocks in another order: round-off, 1e-12 of the largest entry.
template <int dim> void check_relinearised_filter(const Model<dim>& m) {
  const double dt = 0.01;
  TensorFilter<dim> filter(m, dt);
  const int nf = static_cast<int>(m.free_nodes.size());
  Eigen::MatrixXd H0(dim * nf, dim * nf);
  for (int r = 0; r < dim * nf; ++r)
    for (int c = 0; c < dim * nf; ++c) H0(r, c) = filter.entry(r, c);
  // Stretched 40 % along x, sheared, and a little noise: springs stretched and compressed.
  Nodal<dim> u(dim, m.num_nodes());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1, 1);
  const double size = m.net.rest_length.mean();
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Vec<dim> X = m.net.rest.col(i);
    u.col(i).setZero();
    u(0, i) = 0.4 * X.x() + 0.3 * X.y();
    for (int p = 0; p < dim; ++p) u(p, i) += 0.05 * size * noise(rng);
  }
  filter.relinearize(u);
  EXPECT_EQ(filter.relinearizations(), 1);
  const auto J = force_jacobians(m.net, u, true);
  const Eigen::MatrixXd K(J.K), D(J.D);
  double worst = 0, largest = 0;
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b)
      for (int p = 0; p < dim; ++p)
        for (int q = 0; q < dim; ++q) {
          const int r = dim * m.free_nodes[static_cast<std::size_t>(a)] + p;
          const int c = dim * m.free_nodes[static_cast<std::size_t>(b)] + q;
          const double expected = (r == c ? m.net.mass[r / dim] : 0.0) - dt * D(r, c) - dt * dt * K(r, c);
          worst = std::max(worst, std::abs(filter.entry(dim * a + p, dim * b + q) - expected));
          largest = std::max(largest, std::abs(expected));
        }
  EXPECT_LT(worst, 1e-12 * largest);
  EXPECT_LT(filter.prepare(u), 1e-6) << "the shape it was linearised at has no mismatch from itself";
  filter.relinearize(Nodal<dim>::Zero(dim, m.num_nodes()));
  double back = 0;
  for (int r = 0; r < dim * nf; ++r)
    for (int c = 0; c < dim * nf; ++c) back = std::max(back, std::abs(filter.entry(r, c) - H0(r, c)));
  EXPECT_LT(back, 1e-12 * H0.cwiseAbs().maxCoeff());
}

TEST(TensorFilter, RelinearisedMatrixIsTheJacobianAtTheNewShape2D) {
  check_relinearised_filter(model_of<2>(kPlate2));
}
TEST(TensorFilter, RelinearisedMatrixIsTheJacobianAtTheNewShape3D) {
  check_relinearised_filter(model_of<3>(kBox3));
}

TEST(TensorFilter, MatrixIsTheRestJacobianByDifferencesPlusItsTransverseCover2D) {
  check_tensor_filter(model_of<2>(kPlate2));
}
TEST(TensorFilter, MatrixIsTheRestJacobianByDifferencesPlusItsTransverseCover3D) {
  check_tensor_filter(model_of<3>(kBox3));
}

/// The tile-by-tile solve of the tensor filter's H (ordered by nodes) against a dense LU of
/// the same matrix, then again after the values change (the transverse cover) and the factor
/// is refactorised and refreshed. Both are direct solves: they agree to round-off, 1e-12
/// relative (H's condition number is below 1e3 at dt = 10 ms on these meshes).
template <int dim> void expect_block_solve_matches_dense(const Model<dim>& m) {
  for (const double cover : {0.0, 0.5}) {
    const Eigen::SparseMatrix<double> H0 = tensor_filter_matrix(m, 0.01, 0.0), H = tensor_filter_matrix(m, 0.01, cover);
    OrderedLDLT factor(H0, dim);
    ASSERT_TRUE(factor.factorize());
    BlockSolve<dim> solve(factor);
    EXPECT_GT(solve.tiles(), 0u);
    const auto n = H.rows();
    for (int i = 0; i < n; ++i) // a node's coordinates stay together and in order
      EXPECT_EQ(factor.ordered(i), factor.ordered(i - i % dim) + i % dim);
    if (cover > 0) { // new values on the same pattern, as TensorFilter::cover does
      for (int c = 0; c < H.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(H, c); it; ++it) {
          const int r = factor.ordered(static_cast<int>(it.row())), cc = factor.ordered(c);
          if (r <= cc) factor.values()[factor.offset(r, cc)] = it.value();
        }
      ASSERT_TRUE(factor.factorize());
      solve.refresh();
    }
    Eigen::SparseMatrix<double> P(n, n);
    for (int i = 0; i < n; ++i) P.insert(factor.ordered(i), i) = 1.0;
    const Eigen::MatrixXd Hord = Eigen::MatrixXd(P * H * Eigen::SparseMatrix<double>(P.transpose()));
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
    Eigen::VectorXd x = b;
    solve.solve_in_place(Eigen::Map<Nodal<dim>>(x.data(), dim, n / dim));
    const Eigen::VectorXd expected = Hord.lu().solve(b);
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff()) << "cover " << cover;
  }
}

TEST(BlockSolve, MatchesADenseSolveOfTheTensorFilterBeforeAndAfterARefactorisation) {
  expect_block_solve_matches_dense(model_of<2>(kPlate2));
  expect_block_solve_matches_dense(model_of<3>(kBox3));
}

TEST(BlockSolve, TurnsTheValuesInAndOutInItsSweepsAsSeparatePassesWould) {
  // solve_turned (the 2D tensor filter's solve) against the passes it replaces: b_I = R_i^T
  // f_i for the node i = node[I], solve_in_place, then out's column slot[I] = scale R_i y_I.
  // y: the same operations in the same order, equal to the bit. out: the same products,
  // associated with the scale as Eigen's expression may not be, so within a few roundings of
  // scale |y| (4 eps).
  const Model<2> m = model_of<2>(kPlate2);
  const Eigen::SparseMatrix<double> H = tensor_filter_matrix(m, 0.01, 0.0);
  OrderedLDLT factor(H, 2);
  ASSERT_TRUE(factor.factorize());
  const BlockSolve<2> solve(factor);
  const int nb = static_cast<int>(H.rows()) / 2, nodes = nb + 3; // three nodes outside the system
  std::vector<int> node(static_cast<std::size_t>(nodes)), slot(static_cast<std::size_t>(nb));
  std::iota(node.begin(), node.end(), 0);
  std::shuffle(node.begin(), node.end(), std::mt19937(5)); // the first nb: the system's nodes
  for (int I = 0; I < nb; ++I) slot[static_cast<std::size_t>(I)] = nb - 1 - I;
  const Nodal<2> force = Nodal<2>::Random(2, nodes);
  Nodal<2> turn = Nodal<2>::Random(2, nodes);
  turn.colwise().normalize();
  Nodal<2> b(2, nb);
  for (int I = 0; I < nb; ++I) {
    const int i = node[static_cast<std::size_t>(I)];
    Mat<2> R;
    R << turn(0, i), -turn(1, i), turn(1, i), turn(0, i);
    b.col(I) = R.transpose() * force.col(i);
  }
  Nodal<2> expected_y = b;
  solve.solve_in_place(expected_y);
  Nodal<2> expected_out(2, nb);
  for (int I = 0; I < nb; ++I) {
    const int i = node[static_cast<std::size_t>(I)];
    Mat<2> R;
    R << turn(0, i), -turn(1, i), turn(1, i), turn(0, i);
    expected_out.col(slot[static_cast<std::size_t>(I)]) = 0.01 * (R * expected_y.col(I));
  }
  Nodal<2> y = Nodal<2>::Zero(2, nb), out = Nodal<2>::Zero(2, nb);
  solve.solve_turned(force.data(), turn.data(), node.data(), slot.data(), 0.01, y.data(), out.data());
  EXPECT_EQ(y, expected_y);
  const double eps = std::numeric_limits<double>::epsilon();
  EXPECT_LE((out - expected_out).cwiseAbs().maxCoeff(), 4 * eps * 0.01 * expected_y.cwiseAbs().maxCoeff());
  EXPECT_GT(out.cwiseAbs().maxCoeff(), 0.0);
  Nodal<2> y_only = Nodal<2>::Zero(2, nb); // without out: y alone
  solve.solve_turned(force.data(), turn.data(), node.data(), slot.data(), 0.01, y_only.data(), nullptr);
  EXPECT_EQ(y_only, expected_y);
}

TEST(TensorFilter, RigidRotationLeavesNoMismatch) {
  // Warping takes a rigid rotation out exactly: every node's rotation is the body's, and every
  // spring's direction is its rest direction turned by it (mismatch at round-off), while a
  // shear of 5 % turns springs apart from their nodes' rotations (mismatch of that order).
  const Model<2> m = model_of<2>(kPlate2);
  TensorFilter<2> filter(m, 0.01);
  const double angle = 0.7;
  const Mat<2> R = Eigen::Rotation2Dd(angle).toRotationMatrix();
  const Nodal<2> u = R * m.net.rest - m.net.rest;
  filter.rotations(u);
  for (int i = 0; i < m.num_nodes(); ++i) EXPECT_LT((filter.rotation(i) - R).norm(), 1e-12);
  EXPECT_LT(filter.direction_mismatch(u), 1e-12);
  Nodal<2> shear = Nodal<2>::Zero(2, m.num_nodes());
  shear.row(0) = 0.05 * m.net.rest.row(1);
  filter.rotations(shear);
  EXPECT_GT(filter.direction_mismatch(shear), 0.01);
  EXPECT_LT(filter.direction_mismatch(shear), 0.05);
}

TEST(TensorFilter, RotationsAreTheNeighbourhoodsPolarFactorsIn3D) {
  // Each node's rotation is the polar factor of A_i = sum_j (x_j - x_i)(X_j - X_i)^T, the
  // rotation nearest to it (found by a scaled Newton iteration, tensor_filter.cc): against the
  // SVD's U V^T on a rigid rotation and on a rotated random distortion of 15 % of the mesh
  // size. Both are converged to round-off: 1e-12 (|R| = sqrt 3).
  const Model<3> m = model_of<3>(kBox3);
  TensorFilter<3> filter(m, 0.01);
  const Mat<3> R = Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Nodal<3> rigid = R * m.net.rest - m.net.rest;
  filter.rotations(rigid);
  for (int i = 0; i < m.num_nodes(); ++i) EXPECT_LT((filter.rotation(i) - R).norm(), 1e-12);
  EXPECT_LT(filter.direction_mismatch(rigid), 1e-12);
  const Nodal<3> u = R * (m.net.rest + random_state(m, 0.0, 11).u) - m.net.rest;
  filter.rotations(u);
  const auto& net = m.net;
  for (int i = 0; i < net.num_nodes(); ++i) {
    Mat<3> A = Mat<3>::Zero();
    for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p) {
      const int j = net.adj_node[static_cast<std::size_t>(p)];
      A += (net.rest.col(j) + u.col(j) - net.rest.col(i) - u.col(i)) * (net.rest.col(j) - net.rest.col(i)).transpose();
    }
    const Eigen::JacobiSVD<Mat<3>> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    ASSERT_GT(A.determinant(), 0.0) << "node " << i;
    EXPECT_LT((filter.rotation(i) - svd.matrixU() * svd.matrixV().transpose()).norm(), 1e-12) << "node " << i;
  }
}

/// max over springs s = (i, j) of |d/|d| - t/|t||, d the spring's vector at u and t = (R_i +
/// R_j) D its rest vector D turned by its ends' rotations: the mismatch's definition, directly.
template <int dim>
double mismatch_by_definition(const Model<dim>& m, const TensorFilter<dim>& filter, const Nodal<dim>& u) {
  double worst = 0;
  for (const auto& [i, j] : m.net.edge) {
    const Vec<dim> D = m.net.rest.col(j) - m.net.rest.col(i);
    const Vec<dim> d = D + u.col(j) - u.col(i);
    const Vec<dim> t = (filter.rotation(i) + filter.rotation(j)) * D;
    worst = std::max(worst, (d.normalized() - t.normalized()).norm());
  }
  return worst;
}

template <int dim> void check_mismatch(const Model<dim>& m) {
  TensorFilter<dim> filter(m, 0.01);
  Nodal<dim> u = random_state(m, 0.0, 5).u;
  filter.rotations(u);
  EXPECT_GT(filter.direction_mismatch(u), 0.05);
  EXPECT_NEAR(filter.direction_mismatch(u), mismatch_by_definition(m, filter, u), 1e-12);
  const auto [i, j] = m.net.edge.front();
  u.col(i) += 2 * (m.net.rest.col(j) - m.net.rest.col(i)); // node i beyond j: the spring reversed
  filter.rotations(u);
  const double flipped = filter.direction_mismatch(u);
  EXPECT_GT(flipped, std::sqrt(2.0));
  EXPECT_NEAR(flipped, mismatch_by_definition(m, filter, u), 1e-12);
}

TEST(TensorFilter, MismatchIsTheLargestAngleBetweenASpringAndItsTurnedRestVector) {
  // The scan (in 2D a vector loop over per-spring products, in 3D spring by spring) against
  // the definition, on a random distortion of 15 % of the mesh size, and with one node pushed
  // through its neighbours so that a spring turns past 90 degrees (the scan's exact pass). Both
  // compute the same angle by different roundings of a few operations: 1e-12.
  check_mismatch(model_of<2>(kPlate2));
  check_mismatch(model_of<3>(kBox3));
}

/// Implicit Euler's system on the free dofs (dim a + p), assembled: A = M (1 + dt gamma) + the
/// coupling units' c w w^T - dt D - dt^2 K (K clamped under compression) and b = dt (F + dt K
/// v), F the springs' forces at (u, v); the matrix-free correction must apply exactly these.
template <int dim>
std::pair<Eigen::MatrixXd, Eigen::VectorXd> implicit_euler_system(const Model<dim>& m, const State<dim>& s, double dt,
                                                                  const CouplingSet<dim>& couplings) {
  const int n = m.num_nodes();
  const auto J = force_jacobians(m.net, s.u, true);
  const Eigen::MatrixXd Afull = -dt * Eigen::MatrixXd(J.D) - dt * dt * Eigen::MatrixXd(J.K);
  Nodal<dim> f = Nodal<dim>::Zero(dim, n);
  add_internal_forces(m.net, s.u, s.v, f);
  Eigen::VectorXd v(dim * n), fl(dim * n);
  for (int i = 0; i < n; ++i) v.segment<dim>(dim * i) = s.v.col(i), fl.segment<dim>(dim * i) = f.col(i);
  const Eigen::VectorXd bfull = dt * (fl + dt * (Eigen::MatrixXd(J.K) * v));
  const int nf = static_cast<int>(m.free_nodes.size());
  Eigen::MatrixXd A(dim * nf, dim * nf);
  Eigen::VectorXd b(dim * nf);
  for (int a = 0; a < nf; ++a) {
    const int i = m.free_nodes[static_cast<std::size_t>(a)];
    b.segment<dim>(dim * a) = bfull.segment<dim>(dim * i);
    for (int c = 0; c < nf; ++c)
      A.block<dim, dim>(dim * a, dim * c) =
          Afull.block<dim, dim>(dim * i, dim * m.free_nodes[static_cast<std::size_t>(c)]);
    A.block<dim, dim>(dim * a, dim * a) += m.net.mass[i] * Mat<dim>::Identity();
  }
  for (int u = 0; u < couplings.units(); ++u)
    for (int p = 0; p < couplings.size(u); ++p)
      for (int q = 0; q < couplings.size(u); ++q)
        A.block<dim, dim>(dim * couplings.slot(u, p), dim * couplings.slot(u, q)) +=
            couplings.coefficient(u) * couplings.weight(u, p) * couplings.weight(u, q) * Mat<dim>::Identity();
  return {A, b};
}

/// The expected correction's pieces, from the assembled system A x = b at the filter's step
/// x0: r = b - A x0 and z = P r (the filter's own solve), both on the free dofs.
template <int dim>
std::pair<Eigen::VectorXd, Eigen::VectorXd>
residual_and_direction(const Model<dim>& m, TensorFilter<dim>& filter, const Eigen::MatrixXd& A,
                       const Eigen::VectorXd& b, const Eigen::VectorXd& x0, const CouplingSet<dim>& coupling) {
  const int nf = static_cast<int>(m.free_nodes.size());
  const Eigen::VectorXd r = b - A * x0;
  Nodal<dim> r_nodes = Nodal<dim>::Zero(dim, m.num_nodes()), z(dim, nf);
  for (int a = 0; a < nf; ++a) r_nodes.col(m.free_nodes[static_cast<std::size_t>(a)]) = r.segment<dim>(dim * a);
  filter.solve(r_nodes, coupling, 1.0, z);
  return {r, Eigen::Map<const Eigen::VectorXd>(z.data(), dim * nf)};
}

template <int dim> void check_correction(const Model<dim>& m, bool multigrid) {
  const double dt = 0.01;
  const State<dim> s = random_state(m, 1.0, 3); // 15 % distortion: the cover is on
  // A user's pull at one node (dt^2 k + dt b = 40), and a tip's footprint over three nodes
  // (one coupling k w w^T, weights 0.5, 0.3, 0.2 of 4e4 N/m and 20 N s/m).
  Eigen::VectorXd k = Eigen::VectorXd::Zero(m.num_nodes()), damping = k;
  Eigen::VectorXi group = Eigen::VectorXi::Constant(m.num_nodes(), -1);
  damping[m.free_nodes.back()] = 40.0 / dt;
  const std::array<double, 3> w{0.5, 0.3, 0.2};
  for (std::size_t p = 0; p < 3; ++p) {
    const int node = m.free_nodes[p];
    k[node] = w[p] * 4e4, damping[node] = w[p] * 20.0, group[node] = 7;
  }
  CouplingSet<dim> coupling(m.free_index);
  ASSERT_TRUE(coupling.set(k, damping, group, dt));
  ASSERT_EQ(coupling.units(), 2);
  EXPECT_NEAR(coupling.weight(0, 1), 0.3, 1e-15); // the footprint is unit 0 (its nodes come first)
  TensorFilter<dim> filter(m, dt, multigrid);
  ASSERT_GT(filter.prepare(s.u), 2e-3) << "the test needs the cover on";
  Nodal<dim> force = Nodal<dim>::Zero(dim, m.num_nodes());
  add_internal_forces(m.net, s.u, s.v, force, dt); // the filter's F, with its dt k axial term
  const int nf = static_cast<int>(m.free_nodes.size());
  Nodal<dim> dv0(dim, nf), dv(dim, nf);
  filter.solve(force, coupling, dt, dv0);
  const auto [A, b] = implicit_euler_system(m, s, dt, coupling);
  const Eigen::VectorXd x_ie = A.ldlt().solve(b);
  const auto flat = [&](const Nodal<dim>& x) { return Eigen::Map<const Eigen::VectorXd>(x.data(), dim * nf).eval(); };
  const Eigen::VectorXd x0 = flat(dv0);
  const auto [r, zf] = residual_and_direction(m, filter, A, b, x0, coupling);
  const Eigen::VectorXd x1 = x0 + (r.dot(zf) / zf.dot(A * zf)) * zf;
  dv = dv0;
  filter.correct(s.u, s.v, force, coupling, dt, dv);
  // Matrix-free against assembled: the same operations in another order, 1e-10 of the step.
  EXPECT_LT((flat(dv) - x1).norm(), 1e-10 * x1.norm());
  const auto energy = [&](const Eigen::VectorXd& e) { return std::sqrt(e.dot(A * e)); };
  EXPECT_LT(energy(flat(dv) - x_ie), energy(x0 - x_ie)) << "closer to implicit Euler's step";
  EXPECT_GT(energy(x1 - x0), 1e-3 * energy(x0)) << "and by a margin: the test's state departs";
}

TEST(TensorFilter, CorrectionIsOneConjugateGradientStepOnImplicitEulersSystem) {
  // TensorFilter::correct applies implicit Euler's matrix and right-hand side spring by spring;
  // assembled here from the force Jacobians (with mass damping, a coupled node, and the
  // clamp of K's transverse term under compression), the same step must come out, and it is
  // closer to implicit Euler's step in A's energy norm than the filter's own (the line search
  // guarantees it). With the factor in 2D and the block V-cycle in 3D.
  check_correction(model_of<2>(kPlate2), false);
  check_correction(model_of<3>(kBox3), true);
  // At rest nothing departs: the 2D factor with no cover leaves the step as it is.
  const Model<2> m = model_of<2>(kPlate2);
  TensorFilter<2> filter(m, 0.01);
  const State<2> s = initial_state(m);
  filter.prepare(s.u);
  Nodal<2> force = Nodal<2>::Random(2, m.num_nodes());
  Nodal<2> dv(2, static_cast<Eigen::Index>(m.free_nodes.size()));
  const CouplingSet<2> none(m.free_index);
  filter.solve(force, none, 0.01, dv);
  const Nodal<2> before = dv;
  filter.correct(s.u, s.v, force, none, 0.01, dv);
  EXPECT_EQ((dv - before).norm(), 0.0);
}

TEST(TensorFilter, TheVCyclesCorrectionRunsEveryStep) {
  // After a correction whose gain (its share of the step's energy) is below kCorrectionGain, a
  // cover's next kCorrectionRest corrections are skipped: there the small gains moved the error
  // by at most 3 %. The V-cycle's extra mass Delta lags every step alike and small gains add
  // up (a held-out 1,500-node slab press at dt 1 ms: 1.54x implicit Euler's error with the
  // rest, 1.11x without; docs/method.md), so under the V-cycle every call corrects. A smooth
  // state (the box stretched 1 % along x, at rest), where the first correction's gain is small.
  const Model<3> m = model_of<3>(kBox3);
  const double dt = 0.01;
  State<3> s = initial_state(m);
  for (int i = 0; i < m.num_nodes(); ++i) s.u(0, i) = 0.01 * m.net.rest(0, i);
  Nodal<3> force = Nodal<3>::Zero(3, m.num_nodes());
  add_internal_forces(m.net, s.u, s.v, force, dt);
  const int nf = static_cast<int>(m.free_nodes.size());
  const CouplingSet<3> none(m.free_index);
  TensorFilter<3> filter(m, dt, true);
  filter.prepare(s.u);
  Nodal<3> dv0(3, nf);
  filter.solve(force, none, dt, dv0);
  // The first correction's gain, from the assembled system (as check_correction).
  const auto [A, b] = implicit_euler_system(m, s, dt, none);
  const Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(dv0.data(), 3 * nf);
  const auto [r, zf] = residual_and_direction(m, filter, A, b, x0, none);
  const double gain = std::pow(r.dot(zf), 2) / (zf.dot(A * zf) * x0.dot(A * x0));
  ASSERT_LT(gain, TensorFilter<3>::kCorrectionGain) << "the test needs a gain below the threshold";
  ASSERT_GT(gain, 1e-8);
  // Three calls on the same step: each moves it, by the same correction. The move is sqrt(gain)
  // of the step in A's energy norm (about 0.7 % here), so 1e-4 of the step's norm is a margin.
  Nodal<3> first;
  for (int call = 0; call < 3; ++call) {
    Nodal<3> dv = dv0;
    filter.correct(s.u, s.v, force, none, dt, dv);
    EXPECT_GT((dv - dv0).norm(), 1e-4 * dv0.norm()) << "call " << call;
    if (call == 0) first = dv;
    EXPECT_EQ((dv - first).norm(), 0.0) << "call " << call;
  }
}

TEST(TensorFilter, TheCorrectionGoesOnWhereItsStepGainsMuch) {
  // Near incompressibility the V-cycle's extra mass leaves the filter's step far from implicit
  // Euler's: the first correction's gain (its share of the step's energy) is above
  // kCorrectionStepGain, and correct() takes further steps of preconditioned conjugate
  // gradients, each while the last gained more than that, kCorrectionSteps in all at most. A
  // box of nu 0.49 deformed by 15 % of its mesh size. Assembled here: the same iterates, the
  // same stops; matrix-free against assembled to 1e-10 of the step (the operations in another
  // order); and the iterate closer to implicit Euler's step than one step's.
  std::string text = kBox3;
  text.replace(text.find("poisson_ratio = 0.25"), 20, "poisson_ratio = 0.49");
  text.replace(text.find("divisions = [3, 2, 1]"), 21, "divisions = [9, 4, 3]");
  const Model<3> m = model_of<3>(text.c_str());
  const double dt = 0.01;
  const State<3> s = random_state(m, 1.0, 5);
  const CouplingSet<3> none(m.free_index);
  TensorFilter<3> filter(m, dt, true);
  filter.prepare(s.u);
  Nodal<3> force = Nodal<3>::Zero(3, m.num_nodes());
  add_internal_forces(m.net, s.u, s.v, force, dt);
  const int nf = static_cast<int>(m.free_nodes.size());
  Nodal<3> dv0(3, nf);
  filter.solve(force, none, dt, dv0);
  const auto [A, b] = implicit_euler_system(m, s, dt, none);
  const Eigen::VectorXd x_ie = A.ldlt().solve(b);
  const auto precondition = [&](const Eigen::VectorXd& r) {
    Nodal<3> r_nodes = Nodal<3>::Zero(3, m.num_nodes()), z(3, nf);
    for (int a = 0; a < nf; ++a) r_nodes.col(m.free_nodes[static_cast<std::size_t>(a)]) = r.segment<3>(3 * a);
    filter.solve(r_nodes, none, 1.0, z);
    return Eigen::Map<const Eigen::VectorXd>(z.data(), 3 * nf).eval();
  };
  const Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(dv0.data(), 3 * nf);
  const double e0 = x0.dot(A * x0);
  Eigen::VectorXd x = x0, r = b - A * x0, z = precondition(r), p = z, one_step;
  double rz = r.dot(z), gain = 0;
  int steps = 0;
  do {
    const Eigen::VectorXd Ap = A * p;
    const double alpha = rz / p.dot(Ap);
    x += alpha * p;
    gain = rz * rz / (p.dot(Ap) * e0);
    if (++steps == 1) one_step = x;
    r -= alpha * Ap;
    z = precondition(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  } while (steps < TensorFilter<3>::kCorrectionSteps && gain > TensorFilter<3>::kCorrectionStepGain);
  ASSERT_GT(steps, 1) << "the test needs a first gain above the threshold";
  Nodal<3> dv = dv0;
  filter.correct(s.u, s.v, force, none, dt, dv);
  const Eigen::VectorXd got = Eigen::Map<const Eigen::VectorXd>(dv.data(), 3 * nf);
  EXPECT_LT((got - x).norm(), 1e-10 * x.norm());
  EXPECT_EQ(filter.extra_corrections(), steps - 1);
  const auto energy = [&](const Eigen::VectorXd& e) { return std::sqrt(e.dot(A * e)); };
  EXPECT_LT(energy(got - x_ie), energy(one_step - x_ie)) << "closer to implicit Euler's step than one step";
}

template <int dim> Eigen::VectorXd pack(const Model<dim>& m, const State<dim>& s) {
  const int nf = static_cast<int>(m.free_nodes.size());
  Eigen::VectorXd y(2 * dim * nf);
  for (int a = 0; a < nf; ++a)
    for (int p = 0; p < dim; ++p) {
      y[a * dim + p] = s.u(p, m.free_nodes[static_cast<std::size_t>(a)]);
      y[dim * nf + a * dim + p] = s.v(p, m.free_nodes[static_cast<std::size_t>(a)]);
    }
  return y;
}

template <int dim> void check_cvode_jacobian(const Model<dim>& m) {
  // At t = 0.05 the drive has not started (constrained nodes at rest, so the omitted dashpot
  // direction term vanishes with v = 0); the load ramps (its time dependence does not enter
  // dg/dy). Position columns at v = 0, velocity columns at v != 0.
  const double t = 0.05;
  for (double vscale : {0.0, 1.0}) {
    const Eigen::VectorXd y = pack(m, random_state(m, vscale, 11));
    const Eigen::MatrixXd J = cvode_jacobian<dim>(m, t, y);
    const int N = static_cast<int>(y.size()) / 2;
    const double h = 1e-6 * m.net.rest_length.minCoeff();
    const int first = vscale == 0 ? 0 : N, last = vscale == 0 ? N : 2 * N;
    double err = 0, scale = 0;
    for (int c = first; c < last; ++c) {
      Eigen::VectorXd yp = y, ym = y;
      yp[c] += h;
      ym[c] -= h;
      const Eigen::VectorXd fd = (cvode_rhs<dim>(m, t, yp) - cvode_rhs<dim>(m, t, ym)) / (2 * h);
      err = std::max(err, (J.col(c) - fd).cwiseAbs().maxCoeff());
      scale = std::max(scale, J.col(c).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(err, kTol * scale) << (vscale == 0 ? "d/du columns" : "d/dv columns");
  }
}

TEST(CvodeJacobian, MatchesRightHandSideDifferences2D) {
  check_cvode_jacobian(model_of<2>(kPlate2));
}
TEST(CvodeJacobian, MatchesRightHandSideDifferences3D) {
  check_cvode_jacobian(model_of<3>(kBox3));
}
TEST(CvodeJacobian, MatchesRightHandSideDifferencesWithTheVolumeTerm) {
  check_cvode_jacobian(volume_model_of<2>(kPlate2));
  check_cvode_jacobian(volume_model_of<3>(kBox3));
}

template <int dim> void check_implicit_euler_step(const Model<dim>& m) {
  // Linearised backward Euler (Baraff-Witkin) on the free dofs F:
  //   (M - dt D - dt^2 K)_FF dv = dt (f(u, v) + f_ext(t + dt) + dt K v)_F,
  //   v+ = v + dv, u+ = u + dt v+, supports prescribed at t + dt,
  // with K clamped under compression. dt is chosen so that dt D and dt^2 K are of the order of
  // M: a dropped or sign-flipped term changes dv by O(1). A dense LU solve of the same system
  // agrees with the sparse one to round-off times the condition number (< 1e4 here): 1e-9.
  const double dt = 0.01;
  State<dim> s = random_state(m, 1.0, 5);
  s.t = 0.2;
  m.apply_constraints(s.t, s.u, s.v);
  const ForceJacobians<dim> J = force_jacobians(m.net, s.u, true);
  const Eigen::MatrixXd K(J.K), D(J.D);
  const int n = dim * m.num_nodes();
  Eigen::VectorXd mass(n);
  for (int i = 0; i < m.num_nodes(); ++i) mass.segment<dim>(dim * i).setConstant(m.net.mass[i]);
  Nodal<dim> fext(dim, m.num_nodes());
  m.external_forces(s.t + dt, fext);
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(s.v.data(), n);
  const Eigen::VectorXd rhs =
      dt * (forces(m, s.u, s.v) + Eigen::Map<const Eigen::VectorXd>(fext.data(), n) + dt * K * v);
  const Eigen::MatrixXd A = Eigen::MatrixXd(mass.asDiagonal()) - dt * D - dt * dt * K;
  std::vector<int> dofs;
  for (int i : m.free_nodes)
    for (int p = 0; p < dim; ++p) dofs.push_back(dim * i + p);
  const int nf = static_cast<int>(dofs.size());
  Eigen::MatrixXd Aff(nf, nf);
  Eigen::VectorXd bf(nf);
  for (int a = 0; a < nf; ++a) {
    bf[a] = rhs[dofs[static_cast<std::size_t>(a)]];
    for (int b = 0; b < nf; ++b) Aff(a, b) = A(dofs[static_cast<std::size_t>(a)], dofs[static_cast<std::size_t>(b)]);
  }
  // The terms that matter are of the order of M (so the check is sensitive to each).
  const double mmax = mass.maxCoeff();
  EXPECT_GT(dt * dt * K.cwiseAbs().maxCoeff(), 0.3 * mmax);
  EXPECT_GT(dt * (D + Eigen::MatrixXd(mass.asDiagonal()) * m.net.mass_damping).cwiseAbs().maxCoeff(), 0.3 * mmax);
  const Eigen::VectorXd dv = Aff.partialPivLu().solve(bf);
  State<dim> expect = s;
  for (int a = 0; a < nf; ++a) expect.v.data()[dofs[static_cast<std::size_t>(a)]] += dv[a];
  for (int i : m.free_nodes) expect.u.col(i) += dt * expect.v.col(i);
  expect.t = s.t + dt;
  m.apply_constraints(expect.t, expect.u, expect.v);

  ImplicitEuler<dim> ie(m, dt);
  ie.step(s);
  EXPECT_NEAR(s.t, expect.t, 1e-15);
  EXPECT_LT((s.v - expect.v).cwiseAbs().maxCoeff(), 1e-9 * expect.v.cwiseAbs().maxCoeff());
  EXPECT_LT((s.u - expect.u).cwiseAbs().maxCoeff(), 1e-9 * expect.u.cwiseAbs().maxCoeff());
}

// With the volume term the reference's K (clamped) holds its Gauss-Newton blocks, which the
// step's slots must reproduce.
TEST(ImplicitEulerStep, IsTheLinearisedBackwardEulerSystemWithTheVolumeTerm) {
  check_implicit_euler_step(volume_model_of<2>(kPlate2));
  check_implicit_euler_step(volume_model_of<3>(kBox3));
}

TEST(ImplicitEulerStep, IsTheLinearisedBackwardEulerSystem2D) {
  check_implicit_euler_step(model_of<2>(kPlate2));
}
TEST(ImplicitEulerStep, IsTheLinearisedBackwardEulerSystem3D) {
  check_implicit_euler_step(model_of<3>(kBox3));
}

template <int dim> void check_footprint_solve(const Model<dim>& m) {
  // At rest (no cover, R = I) the tensor filter solves with H = tensor_filter_matrix; a
  // footprint's coupling makes it H + c w w^T on each axis. dv = dt (H + U C U^T)^-1 F by a
  // dense solve against the filter's Woodbury update of its factor: the same in exact
  // arithmetic, 1e-10 of dv for the rounding of two solves of a well-conditioned system.
  const double dt = 0.01;
  const int nf = static_cast<int>(m.free_nodes.size());
  Eigen::VectorXd k = Eigen::VectorXd::Zero(m.num_nodes());
  Eigen::VectorXi group = Eigen::VectorXi::Constant(m.num_nodes(), -1);
  const std::array<double, 4> w{0.4, 0.3, 0.2, 0.1};
  for (std::size_t p = 0; p < w.size(); ++p) {
    const int node = m.free_nodes[p + 1];
    k[node] = w[p] * 5e4, group[node] = 0;
  }
  CouplingSet<dim> coupling(m.free_index);
  coupling.set(k, Eigen::VectorXd(), group, dt);
  ASSERT_EQ(coupling.units(), 1);
  TensorFilter<dim> filter(m, dt);
  const State<dim> s = initial_state(m);
  filter.prepare(s.u);
  Nodal<dim> force = Nodal<dim>::Random(dim, m.num_nodes()), dv(dim, nf);
  filter.solve(force, coupling, dt, dv);
  Eigen::MatrixXd H = Eigen::MatrixXd(tensor_filter_matrix(m, dt, 0.0));
  Eigen::VectorXd wf = Eigen::VectorXd::Zero(nf), f(dim * nf);
  for (std::size_t p = 0; p < w.size(); ++p) wf[m.free_index[static_cast<std::size_t>(m.free_nodes[p + 1])]] = w[p];
  for (int a = 0; a < nf; ++a) f.segment<dim>(dim * a) = force.col(m.free_nodes[static_cast<std::size_t>(a)]);
  for (int a = 0; a < nf; ++a)
    for (int c = 0; c < nf; ++c)
      H.block<dim, dim>(dim * a, dim * c) += dt * dt * 5e4 * wf[a] * wf[c] * Mat<dim>::Identity();
  const Eigen::VectorXd expected = dt * H.ldlt().solve(f);
  const Eigen::VectorXd got = Eigen::Map<const Eigen::VectorXd>(dv.data(), dim * nf);
  EXPECT_LT((got - expected).norm(), 1e-10 * expected.norm());
  // And it is not the per-node diagonal bound: that solve differs at the footprint.
  CouplingSet<dim> diagonal(m.free_index);
  diagonal.set(k, Eigen::VectorXd(), Eigen::VectorXi(), dt);
  ASSERT_EQ(diagonal.units(), 4);
  Nodal<dim> dv_diagonal(dim, nf);
  filter.solve(force, diagonal, dt, dv_diagonal);
  EXPECT_GT((dv_diagonal - dv).norm(), 1e-3 * dv.norm());
}

TEST(TensorFilter, SolvesATipsFootprintAsOneCouplingPerAxis) {
  check_footprint_solve(model_of<2>(kPlate2));
  check_footprint_solve(model_of<3>(kBox3));
}

} // namespace
} // namespace vtb
