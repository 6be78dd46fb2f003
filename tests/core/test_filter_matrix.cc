// Properties of the paper's filter matrix W = H^-1 M, H = M + dt C_L + dt^2 K_L.
#include "support/small_models.hh"
#include "vtb/linalg/nodal_solve.hh"
#include "vtb/linalg/selected_inverse.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>

namespace vtb {
namespace {

Eigen::VectorXd free_masses(const Model<2>& m) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(m.free_nodes.size()));
  for (Eigen::Index a = 0; a < v.size(); ++a) v[a] = m.net.mass[m.free_nodes[static_cast<std::size_t>(a)]];
  return v;
}

TEST(SelectedInverse, MatchesTheDenseInverseOnThePattern) {
  // A shifted graph Laplacian of an irregular mesh: SPD with a nontrivial fill pattern.
  const Model<2> m = test::model_from(test::plate_scene(7, 3, ""));
  const Eigen::SparseMatrix<double> H = filter_system_matrix(m, 0.01);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(H).inverse();
  const Eigen::SparseMatrix<double> Z = selected_inverse(H);
  ASSERT_EQ(Z.nonZeros(), H.nonZeros());
  for (int c = 0; c < Z.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      EXPECT_NEAR(it.value(), dense(it.row(), it.col()), 1e-12 * dense.cwiseAbs().maxCoeff());
}

template <int dim> void expect_nodal_solve_matches_dense(const Eigen::SparseMatrix<double>& H) {
  // The filter's all-coordinates solve against a dense LU of the same matrix, each of the dim
  // right-hand sides in the factor's ordering. Both are direct: they agree to round-off,
  // 1e-12 relative at these sizes (condition number of H below 1e3).
  OrderedLDLT factor(H);
  ASSERT_TRUE(factor.factorize());
  const NodalSolve solve(factor);
  EXPECT_GT(solve.factor_nonzeros(), 0u);
  const auto n = H.rows();
  Eigen::SparseMatrix<double> P(n, n); // ordered row = factor.ordered(original row)
  for (int i = 0; i < n; ++i) P.insert(factor.ordered(i), i) = 1.0;
  const Eigen::MatrixXd Hord = Eigen::MatrixXd(P * H * Eigen::SparseMatrix<double>(P.transpose()));
  const Nodal<dim> b = Nodal<dim>::Random(dim, n);
  Nodal<dim> x = b;
  solve.solve_in_place<dim>(x);
  const Eigen::MatrixXd expected = Hord.lu().solve(Eigen::MatrixXd(b.transpose()));
  EXPECT_LT((Eigen::MatrixXd(x.transpose()) - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

TEST(InterleavedOrder, ListsEachNodeAfterItsChildrenAndNotRightAfterOne) {
  // Two chains 0 -> 1 -> 2 -> 6 and 3 -> 4 -> 5 -> 6 (parent pointers), given in that order:
  // the order alternates between them, so no node follows its own child, and the root last.
  const int parent[] = {1, 2, 6, 4, 5, 6, -1};
  EXPECT_EQ(interleaved_order(parent, 7), (std::vector<int>{0, 3, 1, 4, 2, 5, 6}));
  // One chain: nothing else is ever ready, so the given order stands.
  const int chain[] = {1, 2, 3, -1};
  EXPECT_EQ(interleaved_order(chain, 4), (std::vector<int>{0, 1, 2, 3}));
}

TEST(OrderedLDLT, KeepsAmdsFillAndRarelyPutsARowRightAfterOneItNeeds) {
  // The interleaved order is a topological order of AMD's elimination tree, so the factor has
  // AMD's fill exactly (Eigen's own LDL^T with AMD); and on the 517-node plate a row follows a
  // row it needs (L(k + 1, k) != 0) 14 times in 506 (AMD's order alone: 287). A tenth bounds
  // it: only where a single chain is left (the last separator) can the order not avoid it.
  const Model<2> m = test::model_from(test::plate_scene(46, 10, "[[fix]]\ngroup = \"left\"\n"));
  const Eigen::SparseMatrix<double> H = filter_system_matrix(m, 1e-3);
  OrderedLDLT factor(H);
  ASSERT_TRUE(factor.factorize());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> amd(H);
  ASSERT_EQ(amd.info(), Eigen::Success);
  const Eigen::SparseMatrix<double> L_amd = amd.matrixL();
  EXPECT_EQ(factor.lower().nonZeros(), L_amd.nonZeros() - H.rows()); // Eigen's view holds the unit diagonal
  const Eigen::SparseMatrix<double>& L = factor.lower();
  int follows = 0;
  for (Eigen::Index k = 0; k + 1 < L.cols(); ++k) follows += L.coeff(k + 1, k) != 0;
  EXPECT_LT(follows, H.rows() / 10) << "of " << H.rows() << " rows";
}

TEST(OrderedLDLT, FactorisedInPartsIsTheSameFactorToTheBit) {
  // factorize_part runs factorize()'s row loop a share at a time: the same arithmetic in the
  // same order, so L and D are equal to the bit, whatever the share; a share of 0 takes one
  // row per call.
  const Model<2> m = test::model_from(test::plate_scene(30, 8, "[[fix]]\ngroup = \"left\"\n"));
  const Eigen::SparseMatrix<double> H = filter_system_matrix(m, 1e-3);
  OrderedLDLT whole(H), parts(H);
  ASSERT_TRUE(whole.factorize());
  ASSERT_TRUE(parts.factorize());
  const double work = whole.factorize_work();
  ASSERT_GT(work, static_cast<double>(H.rows()));
  for (const double share : {0.0, 0.05, 0.3}) {
    parts.values()[0] *= 2; // other values, then the first ones back: a factor made again
    ASSERT_TRUE(parts.factorize());
    parts.values()[0] /= 2;
    parts.begin_factorize();
    int calls = 1;
    while (!parts.factorize_part(share * work)) ++calls;
    EXPECT_TRUE(parts.factorized());
    if (share == 0.0) {
      EXPECT_EQ(calls, H.rows());
    } else {
      // Every call but the last does at least its share (it stops at the first row past it),
      // so at most 1 / share calls; and more than one, as no row holds the whole.
      EXPECT_LE(calls, static_cast<int>(std::ceil(1 / share))) << share;
      EXPECT_GT(calls, 1) << share;
    }
    const Eigen::SparseMatrix<double> d = parts.lower() - whole.lower();
    EXPECT_EQ(Eigen::MatrixXd(d).cwiseAbs().maxCoeff(), 0.0) << share;
    EXPECT_EQ((parts.diagonal() - whole.diagonal()).cwiseAbs().maxCoeff(), 0.0) << share;
  }
}

TEST(NodalSolve, MatchesADenseSolveForEveryCoordinate) {
  const Model<2> m = test::model_from(test::plate_scene(7, 3, "[[fix]]\ngroup = \"left\"\n"));
  const Eigen::SparseMatrix<double> H = filter_system_matrix(m, 0.01);
  expect_nodal_solve_matches_dense<2>(H);
  expect_nodal_solve_matches_dense<3>(H);
}

TEST(FilterMatrix, FreeBodyRowsSumToOneAndHInverseIsSymmetricAndPositive) {
  const Model<2> m = test::model_from(test::plate_scene(6, 2, ""));
  ASSERT_FALSE(m.has_constraints());
  const Eigen::MatrixXd W = filter_matrix_full(m, 0.01);
  const Eigen::VectorXd mass = free_masses(m);
  // H 1 = M 1 (Laplacians have zero row sums) => W 1 = H^-1 M 1 = 1: W averages accelerations.
  EXPECT_LT((W.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
  // W M^-1 = H^-1 is symmetric; H is an M-matrix so H^-1 >= 0 entrywise.
  const Eigen::MatrixXd Hinv = W * mass.cwiseInverse().asDiagonal();
  EXPECT_LT((Hinv - Hinv.transpose()).cwiseAbs().maxCoeff(), 1e-12 * Hinv.cwiseAbs().maxCoeff());
  EXPECT_GE(W.minCoeff(), 0.0);
  // Column sums weighted by mass: sum_i m_i W_ij = m_j, so the filtered impulses keep the
  // total momentum (the reason W multiplies accelerations, not forces).
  EXPECT_LT(((mass.transpose() * W).transpose() - mass).cwiseAbs().maxCoeff(), 1e-12 * mass.maxCoeff());
}

TEST(FilterMatrix, ConstrainedBodyRowsSumBelowOne) {
  const Model<2> m = test::model_from(test::plate_scene(6, 2, "[[fix]]\ngroup = \"left\"\n"));
  const Eigen::MatrixXd W = filter_matrix_full(m, 0.01);
  EXPECT_LT(W.rowwise().sum().maxCoeff(), 1.0);
  EXPECT_GT(W.rowwise().sum().minCoeff(), 0.0);
}

TEST(FilterMatrix, NeighbourTruncationKeepsExactEntriesAndDropsWeight) {
  const Model<2> m = test::model_from(test::plate_scene(8, 3, ""));
  const double dt = 0.01;
  const Eigen::MatrixXd W = filter_matrix_full(m, dt);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> Wn = filter_matrix_neighbors(m, dt);
  for (int r = 0; r < Wn.outerSize(); ++r) {
    int count = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(Wn, r); it; ++it, ++count)
      EXPECT_NEAR(it.value(), W(it.row(), it.col()), 1e-12);
    const int node = m.free_nodes[static_cast<std::size_t>(r)];
    EXPECT_EQ(count,
              m.net.adj_ptr[static_cast<std::size_t>(node) + 1] - m.net.adj_ptr[static_cast<std::size_t>(node)] + 1)
        << "the node and its mesh neighbours";
  }
  // Truncation drops positive weight: rows sum below the full rows (here, below 1).
  const Eigen::VectorXd rows = Eigen::MatrixXd(Wn).rowwise().sum();
  EXPECT_LT(rows.maxCoeff(), 1.0);
}

TEST(FilterMatrix, TruncatedWLosesDefinitenessAtLargeSteps) {
  // The mechanism behind the neighbour filter's stability limit (docs/method.md): at the
  // explicit limit the truncated W is still positive definite; at 10x it has negative
  // eigenvalues, which turn the damping of the stiffest modes into amplification.
  const Model<2> m = test::model_from(test::plate_scene(8, 2, "", 0.0));
  const double dtc = explicit_critical_dt(max_omega_squared(m, true), 0.0, 0.0);
  auto min_eig = [&](double dt) {
    const Eigen::MatrixXd Wn(filter_matrix_neighbors(m, dt));
    const Eigen::MatrixXd S =
        free_masses(m).cwiseSqrt().asDiagonal() * Wn * free_masses(m).cwiseSqrt().cwiseInverse().asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (S + S.transpose())).eigenvalues().minCoeff();
  };
  EXPECT_GT(min_eig(dtc), 0.0);
  EXPECT_LT(min_eig(10 * dtc), 0.0);
}

} // namespace
} // namespace vtb
