#pragma once
/// \file
/// The LDL^T factor of a matrix made of dim x dim tiles (a node's coordinates: the tensor
/// filter's H), solved tile by tile. OrderedLDLT ordered with block = dim keeps each node's
/// rows consecutive, so L is made of dense dim x dim tiles (zero-padded where the scalar
/// factor has no entry) plus a unit lower tile on the diagonal. As NodalSolve does for the
/// scalar factor, L is kept by tile rows for the forward sweep and by tile columns for the
/// backward sweep, so that both are gathers that accumulate a node's dim values in registers:
/// one index per dim^2 values instead of one per value, and no scatter (docs/performance.md).
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

  /// x <- A^-1 x; x's column k holds the factor's rows k dim .. k dim + dim - 1.
  void solve_in_place(Eigen::Ref<Nodal<dim>> x) const;

  /// Tiles of L below the diagonal (each dim x dim).
  std::size_t tiles() const { return m_col_row.size(); }

private:
  static constexpr int kTile = dim * dim;
  const OrderedLDLT& m_factor;
  std::vector<int> m_col_ptr, m_col_row; ///< tile columns: the tile rows below the diagonal
  std::vector<int> m_row_ptr, m_row_col; ///< tile rows: the tile columns left of the diagonal
  std::vector<int> m_row_tile;           ///< per tile in row order, its index in column order
  std::vector<int> m_source;             ///< per tile value (column order, then diagonal tiles): L's offset, or -1
  std::vector<double> m_col_val, m_row_val, m_diag_val; ///< tiles (column-major), diagonal tiles' strict lower part
  Eigen::VectorXd m_inv_diag;
};

} // namespace vtb
