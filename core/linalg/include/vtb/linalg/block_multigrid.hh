#pragma once
/// \file
/// One fixed symmetric V-cycle of smoothed-aggregation multigrid for an SPD matrix made of
/// dim x dim node blocks (row dim a + p: node a, axis p): the tensor filter's stand-in for
/// H_t^-1 on 3D meshes whose factor of H_t is too large (`filter = "tensor-multigrid"`,
/// docs/method.md). The scalar V-cycle (multigrid.hh) serves the scalar filter's H; this one
/// keeps each node's axes together, as elasticity needs.
///
/// Setup (once): node aggregates of the blocks' graph (aggregation.hh, strength by the
/// blocks' norms); per aggregate, the tentative prolongator is an orthonormal basis of the
/// rigid modes on its nodes (dim translations and dim (dim - 1) / 2 rotations: elasticity's
/// near-kernel, which a coarse space of translations alone misses, so that such a cycle
/// contracted bending's error by only 0.97), smoothed by one damped block-Jacobi step; Galerkin
/// coarse matrices P^T A P with a block of rigid modes per coarse node, down to at most
/// `coarsest` nodes, where a sparse LDL^T solves exactly.
///
/// Apply (nothing allocated): one V(1,1) cycle from x = 0 with node-block Gauss-Seidel,
/// forward before the coarse correction and backward after it. As for the scalar cycle, the
/// post-smoother is the pre-smoother's adjoint and the coarse operators are Galerkin, so
/// 0 < B <= A^-1 and B^-1 = A + Delta with Delta symmetric positive semidefinite.
///
/// The cycle is bound by memory, so it reads the matrices and P in single precision: each
/// matrix rounded symmetrically with each diagonal value raised by its row's rounding errors
/// (BlockCsr::f), so that the stored matrix is >= the exact one and the bound above holds for
/// the exact A; P rounded once and used as rounded everywhere.
///
/// The finest matrix's values may change (the tensor filter's transverse cover): write them
/// through values() and offset(), then refresh() recomputes the diagonal inverses, the coarse
/// matrices (numeric products into the patterns made at setup) and the coarsest factor,
/// without allocating.

#include "vtb/linalg/multigrid.hh"
#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/ordered_ldlt.hh"

#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace vtb {

template <int dim> class BlockMultigrid {
public:
  /// Values per node in the cycle's vectors: 3D nodes are padded to 4 (the pad stays 0).
  static constexpr int kLanes = dim == 3 ? 4 : dim;
  /// A coarse node's values: the rigid modes.
  static constexpr int kModes = dim * (dim + 1) / 2;
  /// A: both triangles stored; its pattern is taken by node blocks (an entry of a block makes
  /// the whole block part of the pattern). x: the nodes' positions (the rigid modes').
  BlockMultigrid(const Eigen::SparseMatrix<double>& A, const Nodal<dim>& x, Eigen::Index coarsest = 64);
  /// A second cycle with this one's hierarchy, so that one can be refreshed while the other
  /// serves (the tensor filter's two systems): what the cycle reads (the matrices in single
  /// precision, the diagonal inverses, the coarsest factor) copied; the prolongators, which
  /// never change, and the values in double, which only a refresh reads, shared. values() is
  /// then the same array for both: write it for the refresh of one, and refresh that one
  /// before the other. About a third of the memory of a second setup, and none of its time.
  BlockMultigrid(const BlockMultigrid& other);
  BlockMultigrid& operator=(const BlockMultigrid&) = delete;

  /// The finest matrix's values: entry (dim a + p, dim b + q) at values()[offset(...)].
  double* values() { return m_mats.front().val().data(); }
  std::size_t value_count() const { return m_mats.front().val().size(); }
  /// Offset into values() of entry (r, c), or -1 where its node block is not in the pattern.
  long offset(int r, int c) const;
  /// After values() changed: the diagonal inverses, coarse matrices and coarsest factor again.
  void refresh();
  /// refresh() in parts, so that a time step can carry a share of it (tensor_filter.hh):
  /// begin_refresh(), then refresh_part(share) until it returns true, each call doing about
  /// `share` of the whole (rows of the Galerkin products, counted in block products; at least
  /// one row). The same arithmetic as refresh(), so the same hierarchy to the bit. Not applied
  /// in between. Allocates nothing.
  void begin_refresh();
  bool refresh_part(double share);

  /// x <- B b; b and x hold kLanes values per node (node a at a kLanes ..), pads 0; distinct.
  void apply(const double* b, double* x);

  int levels() const { return static_cast<int>(m_mats.size()); }
  /// Nodes of each level, finest first (the last is the one solved directly).
  std::vector<Eigen::Index> level_sizes() const;
  /// Bytes held by the matrices, prolongators, coarse factor and work arrays.
  std::size_t memory_bytes() const;

private:
  /// Square node blocks by rows: block k of row i is (i, col[k]), nb x nb values stored as nb
  /// columns of w lanes (value (p, q) at val[k nb w + q w + p]); diag[i]: the diagonal block's k.
  struct BlockCsr {
    int nb = dim, w = kLanes;
    std::vector<int> ptr, col, diag;
    std::vector<int> trans; ///< per block (i, j): the block (j, i)
    /// The level's matrix, in double: where the values are written and the Galerkin products
    /// summed, read only by a refresh (round() makes f from it). A copy of the multigrid
    /// shares it: a refresh of either starts from what was last written.
    std::shared_ptr<std::vector<double>> vals;
    std::vector<double>& val() const { return *vals; }
    /// What the cycle reads: val in single precision, symmetric, each diagonal value raised by
    /// its row's rounding errors, so that the stored matrix is >= val (round()). Packed: value
    /// (p, q) of block k at f[k nb nb + q nb + p] (no pad lanes: a quarter less to read in 3D),
    /// and w - nb floats more at the end, so that a column may be loaded as w lanes (the lanes
    /// past nb read the next values; the sweeps never use them: every stored vector is made by
    /// the padded diagonal inverses).
    std::vector<float> f;
    int rows() const { return static_cast<int>(ptr.size()) - 1; }
    int block() const { return nb * w; }
    int packed() const { return nb * nb; }
  };
  /// What a level's cycle and refreshes read and never change, shared by a copy: P by fine
  /// rows, blocks nbf x nbc stored as nbc columns of wf lanes, its values rounded once (any P
  /// keeps B <= A^-1) and each block transposed (nbf columns of wc lanes, same order); the
  /// pattern of A P by fine rows; the coarse values with no fine support (a small aggregate).
  struct Transfer {
    std::vector<int> pptr, pcol;
    std::vector<float> pval, ptrans;
    std::vector<int> apptr, apcol;
    std::vector<int> dead;
  };
  struct Level {
    std::shared_ptr<const Transfer> t;
    std::vector<double> inv_diag; ///< per node, the inverse diagonal block (as the matrix's blocks)
    std::vector<double> ap_row;   ///< one row of A P, the Galerkin product's scratch
    std::vector<int> marker;      ///< per coarse node: its place in that row
  };
  void cycle(std::size_t l, const double* b, double* x);
  /// Stage `stage` of a refresh, rows [begin, end) where it has rows (else all of it; `end`
  /// past its rows ends it): 0 rounds the finest matrix; 1 + 3 l zeroes level l + 1's matrix
  /// (by its rows), 2 + 3 l adds P^T A P into it by level l's rows and 3 + 3 l rounds it;
  /// 1 + 3 levels is finish(). Returns its work (block products, blocks or rows) and sets
  /// `done` when the stage is complete.
  double refresh_stage(int stage, int begin, int end, bool& done);
  /// The diagonal inverses and the coarsest factor of the levels' current values.
  void finish();
  /// m.f from m.val (BlockCsr::f).
  static void round(BlockCsr& m);
  /// m as a dof-level matrix: every value of every block, zeros included (the setup's products,
  /// the coarsest factor's pattern).
  static Eigen::SparseMatrix<double, Eigen::RowMajor> dofs(const BlockCsr& m);
  /// Level l's fine rows [begin, end) of the Galerkin product: each row i of A P made in the
  /// scratch, then P_i^T (A P)_i added into the coarse matrix, for fine nodes of NB values on W
  /// lanes (coarse: kModes on WC lanes). Returns its block products.
  template <int W, int NB, int WC> double galerkin_rows(std::size_t l, int begin, int end);
  /// The coarsest level's sparse LDL^T, its offsets and ordering (pattern only).
  void make_coarse_factor();
  /// The coarse matrix of level l + 1 from its products: 1 on the dead values, then rounded.
  void finish_coarse(std::size_t l);

  std::vector<BlockCsr> m_mats;              ///< every level's matrix, finest first
  std::vector<Level> m_levels;               ///< every level but the coarsest
  std::vector<std::vector<double>> m_b, m_x; ///< work per coarse level
  std::unique_ptr<OrderedLDLT> m_coarse;     ///< the coarsest level's factor
  std::vector<int> m_coarse_offset;          ///< per coarsest block value: its factor offset, or -1
  std::vector<int> m_coarse_order;           ///< per coarsest dof: its factor row
  Eigen::MatrixXd m_coarse_rhs;              ///< one column in factor order
  int m_stage = 0, m_row = 0;                ///< refresh_part's place: the stage and its next row
  double m_work = 0;                         ///< a whole refresh's work, counted by the last refresh()
};

} // namespace vtb
