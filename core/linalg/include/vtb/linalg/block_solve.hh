#pragma once
/// \file
/// The LDL^T factor of a matrix made of dim x dim tiles (a node's coordinates: the tensor
/// filter's H), solved tile by tile. OrderedLDLT ordered with block = dim keeps each node's
/// rows consecutive, so L is made of dense dim x dim tiles (zero-padded where the scalar
/// factor has no entry) plus a unit lower tile on the diagonal. As NodalSolve does for the
/// scalar factor, L is kept by tile rows for the forward sweep and by tile columns for the
/// backward sweep, so that both are gathers that accumulate a node's dim values in registers:
/// one index per dim^2 values instead of one per value, and no scatter (docs/performance.md).
/// Each node's unit lower tile is folded into its row's and column's tiles, so that a node's
/// values do not wait on each other in the sweeps; in 2D a tile multiplies the node's values
/// spread as (x, x, y, y), in 3D its columns multiply x's values (items 15 and 16 there).
/// refresh() copies a refactorised factor's values in place; nothing allocates after the
/// constructor.

#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/ordered_ldlt.hh"

#include <vector>

namespace vtb {

template <int dim> class BlockSolve {
public:
  /// `factor` must be factorised, ordered with block = dim, and outlive this object.
  explicit BlockSolve(const OrderedLDLT& factor);

  /// Copies the factor's values again after factor.factorize() (same pattern).
  void refresh();

  /// x <- A^-1 x; x's column k holds the factor's rows k dim .. k dim + dim - 1. Not
  /// reentrant in 2D (a scratch vector held here).
  void solve_in_place(Eigen::Ref<Nodal<dim>> x) const;

  /// 2D, with each tile's node turned (the tensor filter's solve, TensorFilter::solve, in the
  /// sweeps instead of passes of their own): y <- A^-1 b, b_I = R_i^T f_i for i = node[I], R_i
  /// the rotation by (cos, sin) = turn's column i, f = force's column i (both 2 x nodes); and
  /// where out is given, out's column slot[I] = scale R_i y_I.
  void solve_turned(const double* force, const double* turn, const int* node, const int* slot, double scale, double* y,
                    double* out) const;

  /// Tiles of L below the diagonal (each dim x dim).
  std::size_t tiles() const { return m_col_row.size(); }

private:
  /// 2D: both sweeps, b_I = in(I) (a pair), out(I, x0, x1) with each solved node.
  template <class In, class Out> void spread_solve(int nb, In in, Out out) const;
  static constexpr int kTile = dim * dim;
  const OrderedLDLT& m_factor;
  std::vector<int> m_col_ptr, m_col_row; ///< tile columns: the tile rows below the diagonal
  std::vector<int> m_row_ptr, m_row_col; ///< tile rows: the tile columns left of the diagonal
  std::vector<int> m_row_tile;           ///< per tile in row order, its index in column order
  std::vector<int> m_source;             ///< per tile value (column order, then diagonal tiles): L's offset, or -1
  std::vector<double> m_row_val;         ///< tiles in row order, L_II^-1 L_IJ column-major (one value of padding)
  std::vector<double> m_col_val;         ///< tiles in column order, L_JJ^-T L_IJ^T column-major (one value of padding)
  std::vector<double> m_diag_val;        ///< diagonal tiles' strict lower part (column-major)
  mutable std::vector<double> m_spread;  ///< 2D: the solve's scratch, each node's (x, y) as (x, x, y, y)
  Eigen::VectorXd m_inv_diag;
};

} // namespace vtb
