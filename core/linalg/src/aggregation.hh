#pragma once
/// \file
/// Smoothed aggregation's two setup steps, shared by the scalar V-cycle (multigrid.hh) and the
/// block one (block_multigrid.hh): the aggregates of a matrix graph and the smoothed
/// prolongator. Internal to vtb::linalg.

#include <Eigen/SparseCore>

#include <vector>

namespace vtb::detail {

using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;
/// A node's block (at most 6 x 6: a 3D coarse node's rigid modes), on the stack.
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

/// Aggregate of each row of A (graph of the off-diagonal entries |a_ij| >= theta sqrt(a_ii
/// a_jj)); returns their count.
int aggregate(const RowSparse& A, std::vector<int>& agg, double theta = 0.04);
/// aggregate() by the strong couplings, made again of every coupling (theta = 0) where they
/// coarsen A's rows less than kMinCoarsening times (multigrid.hh); returns their count.
int aggregate_tenfold(const RowSparse& A, std::vector<int>& agg);

/// P = (I - w D^-1 A) P0, P0 the aggregates' indicator, w = 4/3 over an estimate of the
/// spectral radius of D^-1 A.
RowSparse smoothed_prolongator(const RowSparse& A, const std::vector<int>& agg, int nc);

} // namespace vtb::detail
