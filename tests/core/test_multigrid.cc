// The multigrid filter: one symmetric V-cycle B standing in for H^-1 (core/multigrid.hh).
// What the filter's stability rests on is checked on B itself (symmetric, 0 < B <= H^-1) and
// on the linearised filtered step (spectral radius at most 1 at any multiple of the explicit
// step); what it costs in accuracy is measured in docs/performance.md.
#include "support/small_models.hh"
#include "vtb/linalg/block_multigrid.hh"
#include "vtb/linalg/multigrid.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"
#include "vtb/solvers/tensor_filter.hh"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace vtb {
namespace {

Model<3> box_model(const std::string& extra, double tau = 0.05, const std::string& divisions = "6, 3, 3") {
  const std::string text = R"(
[scene]
duration = 1.0
output_interval = 0.1
[mesh]
generate = { shape = "box", size = [0.12, 0.04, 0.04], divisions = [)" +
                           divisions + R"(] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.25
density = 1000.0
retardation_time = )" + std::to_string(tau) +
                           "\n" + extra;
  const Scene s = parse_scene(text, "box.toml", ".");
  return build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
}

/// B as a dense matrix, column k = B e_k, from coordinate 0 of a dim = 2 apply; coordinate 1
/// carries -e_k and must come out as -B e_k (the coordinates share the cycle but not values).
Eigen::MatrixXd dense_cycle(SymmetricMultigrid<2>& mg, Eigen::Index n) {
  Eigen::MatrixXd B(n, n);
  Nodal<2> b = Nodal<2>::Zero(2, n), x(2, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    b.col(k) << 1.0, -1.0;
    mg.apply(b, x);
    b.col(k).setZero();
    B.col(k) = x.row(0).transpose();
    EXPECT_EQ((x.row(0) + x.row(1)).cwiseAbs().maxCoeff(), 0.0);
  }
  return B;
}

/// The generalised eigenvalues of B against H^-1: those of L^T B L with H = L L^T.
Eigen::VectorXd relative_spectrum(const Eigen::MatrixXd& B, const Eigen::MatrixXd& H) {
  const Eigen::MatrixXd L = H.llt().matrixL();
  const Eigen::MatrixXd S = L.transpose() * B * L;
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (S + S.transpose())).eigenvalues();
}

/// A cycle's dense matrix B against H: symmetric up to round-off (the post-smoother is the
/// pre-smoother's adjoint and the coarse operators are Galerkin, P^T A P, so B = B^T in exact
/// arithmetic), 0 < B <= H^-1 (the eigenvalues of B H lie in (0, 1]: E = I - B H is
/// H-self-adjoint and positive semidefinite; round-off 1e-10 on a matrix of condition below
/// 1e4), and a contraction 1 - min eig(B H) below `worst`.
void expect_symmetric_contraction_below_the_inverse(const Eigen::MatrixXd& B, const Eigen::SparseMatrix<double>& H,
                                                    double worst) {
  EXPECT_LT((B - B.transpose()).cwiseAbs().maxCoeff(), 1e-12 * B.cwiseAbs().maxCoeff());
  const Eigen::VectorXd lambda = relative_spectrum(B, Eigen::MatrixXd(H));
  EXPECT_GT(lambda.minCoeff(), 0.0);
  EXPECT_LE(lambda.maxCoeff(), 1.0 + 1e-10);
  EXPECT_LT(1.0 - lambda.minCoeff(), worst);
}

/// `worst`: the contraction 1 - min eig(B H) the cycle must beat on this H. A smoothed-
/// aggregation V(1,1) cycle contracts the error by a factor independent of the mesh, about 0.4
/// on these meshes (0.42 on the 9,864-node slab; docs/performance.md). 0.6 separates it from a
/// cycle whose coarse correction is broken (Gauss-Seidel alone contracts the smooth modes by
/// 1 - O(h^2): above 0.9 here). Both aggregations; with `tenfold` the coarsest level holds at
/// most 4 rows: these meshes have a few hundred nodes, and levels that coarsen tenfold would
/// reach 16 rows in one, leaving no level between the finest and the direct solve to test.
void expect_one_cycle_is_a_contraction_below_the_inverse(const Eigen::SparseMatrix<double>& H, double worst,
                                                         Aggregates aggregates) {
  SymmetricMultigrid<2> mg(H, aggregates == Aggregates::tenfold ? 4 : 16, aggregates);
  const std::vector<Eigen::Index> sizes = mg.level_sizes();
  ASSERT_GE(sizes.size(), 3u) << "a hierarchy of at least three levels";
  for (std::size_t l = 1; l < sizes.size(); ++l) EXPECT_LT(sizes[l], sizes[l - 1]);
  expect_symmetric_contraction_below_the_inverse(dense_cycle(mg, H.rows()), H, worst);
}
void expect_cycle_is_a_contraction_below_the_inverse(const Eigen::SparseMatrix<double>& H, double worst = 0.6) {
  for (const auto aggregates : {Aggregates::strong, Aggregates::tenfold})
    expect_one_cycle_is_a_contraction_below_the_inverse(H, worst, aggregates);
}

TEST(MultigridCycle, IsSymmetricAndBetweenZeroAndTheInverseIn2D) {
  const Model<2> m = test::model_from(test::plate_scene(24, 6, "[[fix]]\ngroup = \"left\"\n"));
  expect_cycle_is_a_contraction_below_the_inverse(filter_system_matrix(m, 0.01));
}

TEST(MultigridCycle, IsSymmetricAndBetweenZeroAndTheInverseIn3D) {
  // Lloyd's springs (within 0.23x..3.2x of their mean here): the mesh's Laplacian, on which
  // the 0.6 bound above was measured (0.35 clamped, 0.37 free).
  const std::string lloyd = "[solver]\nsprings = \"lloyd\"\n";
  const Model<3> m = box_model("[[fix]]\ngroup = \"left\"\n" + lloyd, 0.05, "12, 4, 4");
  expect_cycle_is_a_contraction_below_the_inverse(filter_system_matrix(m, 0.01));
  // A free body too: H is then M plus a singular Laplacian.
  const Model<3> free = box_model(lloyd, 0.05, "12, 4, 4");
  expect_cycle_is_a_contraction_below_the_inverse(filter_system_matrix(free, 0.01));
}

TEST(MultigridCycle, StaysBelowTheInverseOnSpringsOfHighContrast) {
  // Fitted springs vary from spring to spring: an earlier fit spread the free box's from 0.11x
  // to 37x their mean, and the aggregates, built on the mesh's graph with one strength
  // threshold, follow such contrast less well (contraction 0.56 clamped and 0.77 free,
  // docs/performance.md). Here the default springs are scattered log-uniformly over 0.1x .. 30x
  // (fixed seed), more than any fit has produced. What the filter's stability rests on
  // (0 < B <= H^-1) must hold all the same; the bound is the one that separates a working
  // coarse correction from Gauss-Seidel alone (above 0.9, the comment above).
  for (const char* fix : {"[[fix]]\ngroup = \"left\"\n", ""}) {
    Model<3> m = box_model(fix, 0.05, "12, 4, 4");
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> spread(std::log(0.1), std::log(30.0));
    for (Eigen::Index s = 0; s < m.net.stiffness.size(); ++s) m.net.stiffness[s] *= std::exp(spread(rng));
    ASSERT_GT(m.net.stiffness.maxCoeff(), 10 * m.net.stiffness.mean()) << "a high-contrast network";
    expect_cycle_is_a_contraction_below_the_inverse(filter_system_matrix(m, 0.01), 0.9);
  }
}

/// The block cycle B as a dense matrix (column k = B e_k, node-major dofs).
template <int dim> Eigen::MatrixXd dense_block_cycle(BlockMultigrid<dim>& mg, Eigen::Index n) {
  constexpr int W = BlockMultigrid<dim>::kLanes;
  const Eigen::Index nodes = n / dim;
  Eigen::MatrixXd B(n, n);
  std::vector<double> b(static_cast<std::size_t>(nodes * W), 0.0), x(b.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    b[static_cast<std::size_t>((k / dim) * W + k % dim)] = 1.0;
    mg.apply(b.data(), x.data());
    b[static_cast<std::size_t>((k / dim) * W + k % dim)] = 0.0;
    for (Eigen::Index r = 0; r < n; ++r) B(r, k) = x[static_cast<std::size_t>((r / dim) * W + r % dim)];
    for (Eigen::Index a = 0; a < nodes; ++a)
      for (int p = dim; p < W; ++p) EXPECT_EQ(x[static_cast<std::size_t>(a * W + p)], 0.0) << "the pad stays 0";
  }
  return B;
}

/// The block cycle on H: symmetric, 0 < B <= H^-1, and contracting by less than `worst`.
/// The free nodes' rest positions: the rigid modes' coordinates.
template <int dim> Nodal<dim> free_positions(const Model<dim>& m) {
  Nodal<dim> x(dim, static_cast<Eigen::Index>(m.free_nodes.size()));
  for (std::size_t a = 0; a < m.free_nodes.size(); ++a)
    x.col(static_cast<Eigen::Index>(a)) = m.net.rest.col(m.free_nodes[a]);
  return x;
}

template <int dim>
void expect_block_cycle_is_a_contraction_below_the_inverse(const Model<dim>& m, double dt, double worst) {
  const Eigen::SparseMatrix<double> H = tensor_filter_matrix(m, dt);
  BlockMultigrid<dim> mg(H, free_positions(m), 16);
  const std::vector<Eigen::Index> sizes = mg.level_sizes();
  ASSERT_GE(sizes.size(), 3u) << "a hierarchy of at least three levels";
  // As for the scalar cycle: symmetric in exact arithmetic, B H's eigenvalues in (0, 1]. The
  // cycle reads its matrices in single precision, each diagonal raised by its row's rounding
  // errors so that the stored matrix is >= H: without that raise the largest eigenvalue was
  // 1 + O(1e-8) here, beyond the 1e-10 bound (double round-off on these small matrices).
  expect_symmetric_contraction_below_the_inverse(dense_block_cycle(mg, H.rows()), H, worst);
}

TEST(BlockMultigridCycle, IsSymmetricAndBetweenZeroAndTheInverseOfTheTensorFiltersMatrix) {
  // H_t = M + dt D_0 + dt^2 K_0 with the springs' dim x dim blocks: elasticity's coupling of
  // the axes, whose near-kernel (the rigid modes) the coarse spaces carry. Measured 0.74 / 0.74
  // / 0.67 (clamped box, free box, plate); with translations alone in the coarse space the same
  // cycle contracted by 0.97 / 0.98 / 0.93, no better than Gauss-Seidel alone. 0.85 separates
  // the two with the margin of the scalar cycle's bound above.
  const std::string lloyd = "[solver]\nsprings = \"lloyd\"\n";
  const Model<3> clamped = box_model("[[fix]]\ngroup = \"left\"\n" + lloyd, 0.05, "12, 4, 4");
  expect_block_cycle_is_a_contraction_below_the_inverse<3>(clamped, 0.01, 0.85);
  const Model<3> free = box_model(lloyd, 0.05, "12, 4, 4");
  expect_block_cycle_is_a_contraction_below_the_inverse<3>(free, 0.01, 0.85);
  const Model<2> plate = test::model_from(test::plate_scene(24, 6, "[[fix]]\ngroup = \"left\"\n"));
  expect_block_cycle_is_a_contraction_below_the_inverse<2>(plate, 0.01, 0.85);
}

#ifdef VTB_HAVE_CGAL_MESHERS // the block comes from CGAL Mesh_3 (VTB_WITH_CGAL=OFF skips it)
/// A CGAL tissue block of 900 nodes at nu 0.49, bottom clamped, with its fitted springs.
Model<3> tissue_block_nu049() {
  const Scene s = parse_scene(R"(
[scene]
duration = 1.0
output_interval = 0.1
[mesh]
generate = { shape = "box", size = [0.04, 0.04, 0.03], mesher = "cgal", nodes = 900 }
[material]
young_modulus = 5.0e3
poisson_ratio = 0.49
density = 1000.0
retardation_time = 0.05
[[fix]]
group = "bottom"
)",
                              "tissue.toml", ".");
  return build_model<3>(s, std::get<Mesh3>(load_mesh(s)));
}

TEST(BlockMultigridCycle, CoarsensTenfoldNearIncompressibility) {
  // At nu near 1/2 the springs' blocks spread in norm, and aggregates of the strong couplings
  // alone stay small (CGAL tissue blocks at nu 0.49 coarsened 6-7x, to coarse rows so dense
  // that the 6,914-node block's cycle took 85 MB and 40 ms). A level whose strong aggregates
  // coarsen less than kMinCoarsening aggregates by every coupling instead. The 900-node block:
  // the strong aggregates coarsened its first level 6.9x (780 -> 113 free nodes); now at least
  // tenfold.
  const Model<3> m = tissue_block_nu049();
  const Eigen::SparseMatrix<double> H = tensor_filter_matrix(m, 1e-3);
  BlockMultigrid<3> mg(H, free_positions(m), 16);
  const std::vector<Eigen::Index> sizes = mg.level_sizes();
  ASSERT_GE(sizes.size(), 2u);
  EXPECT_GE(sizes[0], kMinCoarsening * sizes[1]);
}

TEST(MultigridCycle, CoarsensTenfoldNearIncompressibility) {
  // The scalar cycle as implicit Euler's CG preconditioner (above 4,000 nodes) on the scalar
  // filter matrix, under the same rule (Aggregates::tenfold): its strong aggregates coarsened
  // the 900-node block's first level 6.0x (780 -> 129 free nodes); a 2,400-node one 6.5x (14.5x
  // at nu 0.25).
  const Model<3> m = tissue_block_nu049();
  const SymmetricMultigrid<3> mg(filter_system_matrix(m, 1e-3), 16, Aggregates::tenfold);
  const std::vector<Eigen::Index> sizes = mg.level_sizes();
  ASSERT_GE(sizes.size(), 2u);
  EXPECT_GE(sizes[0], kMinCoarsening * sizes[1]);
}
#endif

TEST(BlockMultigridCycle, RefreshedAfterNewValuesIsBetweenZeroAndTheirInverse) {
  // The tensor filter's cover changes H's values, not its pattern: refresh() recomputes the
  // hierarchy's values in place (the Galerkin products with the first setup's P). The
  // refreshed cycle must use the new values (it differs from the old B) and keep B's defining
  // property on them: symmetric, 0 < B <= H1^-1.
  const Model<3> m = box_model("[[fix]]\ngroup = \"left\"\n", 0.05, "12, 4, 4");
  const Eigen::SparseMatrix<double> H0 = tensor_filter_matrix(m, 0.01, 0.0), H1 = tensor_filter_matrix(m, 0.01, 0.7);
  BlockMultigrid<3> mg(H0, free_positions(m), 16);
  const Eigen::MatrixXd B0 = dense_block_cycle(mg, H0.rows());
  for (Eigen::Index c = 0; c < H1.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(H1, c); it; ++it) {
      const long off = mg.offset(static_cast<int>(it.row()), static_cast<int>(it.col()));
      ASSERT_GE(off, 0);
      mg.values()[off] = it.value();
    }
  mg.refresh();
  const Eigen::MatrixXd B1 = dense_block_cycle(mg, H1.rows());
  EXPECT_GT((B1 - B0).cwiseAbs().maxCoeff(), 1e-3 * B0.cwiseAbs().maxCoeff()) << "the new values are used";
  EXPECT_LT((B1 - B1.transpose()).cwiseAbs().maxCoeff(), 1e-12 * B1.cwiseAbs().maxCoeff());
  const Eigen::VectorXd lambda = relative_spectrum(B1, Eigen::MatrixXd(H1));
  EXPECT_GT(lambda.minCoeff(), 0.0);
  EXPECT_LE(lambda.maxCoeff(), 1.0 + 1e-10);
  // (A fresh setup on H1 would aggregate and smooth P on H1's values, so its B differs; what
  // the filter's stability needs is the property above, with P from H0.)
}

TEST(BlockMultigridCycle, RefreshedInPartsIsTheSameCycleToTheBit) {
  // refresh_part runs refresh()'s stages a share at a time (rows of the Galerkin products):
  // the same arithmetic in the same order, so the same cycle to the bit. Every call but the
  // last does at least its share of the counted work (it stops at the first chunk of rows past
  // it; a stage that cannot be split, a rounding or finish(), may take it further), so a share
  // of 1/16 takes at most 16 calls and one more, and more than one.
  const Model<3> m = box_model("[[fix]]\ngroup = \"left\"\n", 0.05, "12, 4, 4");
  const Eigen::SparseMatrix<double> H0 = tensor_filter_matrix(m, 0.01, 0.0), H1 = tensor_filter_matrix(m, 0.01, 0.7);
  BlockMultigrid<3> whole(H0, free_positions(m), 16), parts(H0, free_positions(m), 16);
  for (BlockMultigrid<3>* mg : {&whole, &parts})
    for (Eigen::Index c = 0; c < H1.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(H1, c); it; ++it)
        mg->values()[mg->offset(static_cast<int>(it.row()), static_cast<int>(it.col()))] = it.value();
  whole.refresh();
  parts.begin_refresh();
  int calls = 1;
  while (!parts.refresh_part(1.0 / 16)) ++calls;
  EXPECT_LE(calls, 17);
  EXPECT_GE(calls, 2);
  const Eigen::MatrixXd Bw = dense_block_cycle(whole, H1.rows()), Bp = dense_block_cycle(parts, H1.rows());
  EXPECT_EQ((Bw - Bp).cwiseAbs().maxCoeff(), 0.0);
}

TEST(BlockMultigridCycle, ACopyAppliesTheSameCycleAndIsRefreshedWhileTheOriginalServes) {
  // The tensor filter's second system is a copy (block_multigrid.hh): the same cycle to the
  // bit; new values written for the copy and refreshed there leave the original's cycle as it
  // was (it reads its own single-precision matrices), and the original refreshed afterwards
  // takes the same values (the values in double are shared), so the same cycle as the copy's.
  const Model<3> m = box_model("[[fix]]\ngroup = \"left\"\n", 0.05, "12, 4, 4");
  const Eigen::SparseMatrix<double> H0 = tensor_filter_matrix(m, 0.01, 0.0), H1 = tensor_filter_matrix(m, 0.01, 0.7);
  BlockMultigrid<3> mg(H0, free_positions(m), 16);
  const Eigen::MatrixXd B0 = dense_block_cycle(mg, H0.rows());
  BlockMultigrid<3> copy(mg);
  EXPECT_EQ((dense_block_cycle(copy, H0.rows()) - B0).cwiseAbs().maxCoeff(), 0.0);
  for (Eigen::Index c = 0; c < H1.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(H1, c); it; ++it)
      copy.values()[copy.offset(static_cast<int>(it.row()), static_cast<int>(it.col()))] = it.value();
  copy.begin_refresh();
  while (!copy.refresh_part(1.0 / 16)) {
    EXPECT_EQ((dense_block_cycle(mg, H0.rows()) - B0).cwiseAbs().maxCoeff(), 0.0) << "the original serves unchanged";
  }
  const Eigen::MatrixXd B1 = dense_block_cycle(copy, H1.rows());
  EXPECT_EQ((dense_block_cycle(mg, H0.rows()) - B0).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT((B1 - B0).cwiseAbs().maxCoeff(), 1e-3 * B0.cwiseAbs().maxCoeff()) << "the copy uses the new values";
  mg.refresh();
  EXPECT_EQ((dense_block_cycle(mg, H1.rows()) - B1).cwiseAbs().maxCoeff(), 0.0);
}

/// The filtered step linearised at rest, by central differences of one step from a perturbed
/// state: columns are d(u', v') / d(u, v) over the free nodes' coordinates.
Eigen::MatrixXd linearised_step(const Model<3>& model, Integrator<3>& integ) {
  const auto& free = model.free_nodes;
  const auto nf = static_cast<Eigen::Index>(free.size());
  const Eigen::Index n = 6 * nf;
  // Springs are smooth: a central difference is exact to O(eps^2 / L^2) relative, 1e-12 at
  // eps = 1e-8 m on this 2 cm mesh, far below the 1e-6 the spectral radius is tested to.
  const double eps = 1e-8;
  auto stepped = [&](Eigen::Index k, double sign) {
    State<3> s = initial_state(model);
    const Eigen::Index a = (k % (3 * nf)) / 3, c = k % 3;
    const int i = free[static_cast<std::size_t>(a)];
    (k < 3 * nf ? s.u : s.v)(c, i) += sign * eps;
    integ.step(s);
    Eigen::VectorXd y(n);
    for (Eigen::Index b = 0; b < nf; ++b) {
      y.segment<3>(3 * b) = s.u.col(free[static_cast<std::size_t>(b)]);
      y.segment<3>(3 * nf + 3 * b) = s.v.col(free[static_cast<std::size_t>(b)]);
    }
    return y;
  };
  Eigen::MatrixXd G(n, n);
  for (Eigen::Index k = 0; k < n; ++k) G.col(k) = (stepped(k, 1) - stepped(k, -1)) / (2 * eps);
  return G;
}

TEST(MultigridFilter, LinearisedStepNeverAmplifiesAtAnyStep) {
  // The undamped clamped box (no retardation, no mass damping: the hardest case). B^-1 = H +
  // Delta with Delta >= 0, so the multigrid step is the full filter's with extra mass; both are
  // linearised backward Euler with a positive definite mass, whose amplification has spectral
  // radius <= 1 at every dt. Checked from the explicit step to 1000 times it.
  const Model<3> model = box_model("[[fix]]\ngroup = \"left\"\n", 0.0);
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  // The tensor filter's block V-cycle the same way: B_t^-1 = H_t + Delta_t, its step the
  // tensor filter's (linearised backward Euler at rest) with extra mass.
  for (const char* filter :
       {solvers::kFilterFull, solvers::kFilterMultigrid, solvers::kFilterTensor, solvers::kFilterTensorMultigrid})
    for (double mult : {1.0, 10.0, 100.0, 1000.0}) {
      IntegratorOptions o;
      o.kind = solvers::kFiltered;
      o.filter = filter;
      o.dt = mult * dtc;
      auto integ = make_integrator(model, o);
      const Eigen::MatrixXd G = linearised_step(model, *integ);
      const double rho = G.eigenvalues().cwiseAbs().maxCoeff();
      EXPECT_LE(rho, 1.0 + 1e-6) << filter << " at " << mult << "x the explicit step";
    }
}

TEST(MultigridFilter, AutoPicksTheLagFreeFilterUpTo12kFreeNodesAndTheScalarVCycleBeyond) {
  // The default filter: in 3D the lag-free tensor filter by its factor on small meshes, by its
  // block V-cycle from kTensorCycleFreeNodes3D free nodes, and the scalar V-cycle from
  // kScalarCycleFreeNodes3D (docs/method.md); in 2D the tensor filter; a named filter is kept.
  const Model<3> huge = box_model("[[fix]]\ngroup = \"left\"\n", 0.05, "30, 20, 20");
  ASSERT_GE(huge.free_nodes.size(), kScalarCycleFreeNodes3D);
  const Model<3> large = box_model("[[fix]]\ngroup = \"left\"\n", 0.05, "20, 14, 14");
  ASSERT_GE(large.free_nodes.size(), kLargeFreeNodes3D);
  ASSERT_LT(large.free_nodes.size(), kScalarCycleFreeNodes3D);
  const Model<3> small = box_model("[[fix]]\ngroup = \"left\"\n");
  ASSERT_LT(small.free_nodes.size(), kTensorCycleFreeNodes3D);
  const Model<2> plate = test::model_from(test::plate_scene(70, 60, ""));
  ASSERT_GE(plate.free_nodes.size(), kLargeFreeNodes3D);
  EXPECT_EQ(chosen_filter(huge, solvers::kFilterAuto), solvers::kFilterMultigrid);
  EXPECT_EQ(chosen_filter(large, solvers::kFilterAuto), solvers::kFilterTensorMultigrid);
  EXPECT_EQ(chosen_filter(small, solvers::kFilterAuto), solvers::kFilterTensor);
  EXPECT_EQ(chosen_filter(plate, solvers::kFilterAuto), solvers::kFilterTensor) << "2D: the lag-free filter";
  EXPECT_EQ(chosen_filter(large, solvers::kFilterTensor), solvers::kFilterTensor);

  // The integrator runs what was picked, and its step moves the loaded box.
  IntegratorOptions o;
  o.kind = solvers::kFiltered;
  o.dt = 1e-2;
  const Model<3> pulled = box_model(
      "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.0, 0.0, -0.5]\n", 0.05, "20, 14, 14");
  FilteredImplicit<3> f(pulled, o);
  EXPECT_EQ(f.filter(), solvers::kFilterTensorMultigrid);
  State<3> s = initial_state(pulled);
  f.step(s);
  EXPECT_TRUE(s.u.allFinite());
  EXPECT_GT(s.u.norm(), 0.0);
}

} // namespace
} // namespace vtb
