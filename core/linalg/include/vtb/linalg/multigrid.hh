#pragma once
/// \file
/// One fixed symmetric V-cycle of smoothed-aggregation algebraic multigrid for a scalar SPD
/// matrix A, applied to dim right-hand sides at once (a dim x n Nodal, like NodalSolve): the
/// `multigrid` filter's stand-in for H^-1 when a direct factor of H is too large (3D meshes of
/// thousands of nodes; docs/performance.md measures where).
///
/// Setup (once): aggregates of the matrix graph (greedy, in row order: a node whose neighbours
/// are all unassigned seeds an aggregate of itself and them; every other node joins the
/// neighbouring aggregate it is most strongly coupled to), the tentative prolongator P0 (one 1
/// per row), smoothed by one damped Jacobi step P = (I - w D^-1 A) P0 with w = 4/3 over a
/// Gershgorin bound of rho(D^-1 A), and the Galerkin coarse matrix P^T A P; down to at most
/// `coarsest` rows, where a sparse LDL^T solves exactly.
///
/// Apply (per step, nothing allocated): x = B b by one V(1,1) cycle from x = 0, forward
/// Gauss-Seidel before the coarse correction and backward Gauss-Seidel after it. The
/// post-smoother is the pre-smoother's adjoint and the coarse operators are Galerkin, so B is
/// symmetric and the error propagator E = I - B A is A-self-adjoint with its spectrum in
/// [0, 1): 0 < B <= A^-1. That is what the filter's stability rests on (docs/method.md):
/// B^-1 = A + Delta with Delta symmetric positive semidefinite, so a step filtered by B is the
/// filtered step with the extra mass Delta.

#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/nodal_solve.hh"

#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace vtb {

/// The least coarsening a level's strong-coupling aggregates must reach (fine rows per coarse
/// row), else the level aggregates by every coupling: the block cycle's rule, and the scalar
/// cycle's where it preconditions (Aggregates::tenfold). Measured at the first level of the
/// block cycle: the 9,864-node slab at nu 0.25 16.4x (kept), CGAL tissue blocks at nu 0.49
/// 7.1x (2,236 free nodes) and 6.0x (6,551), by every coupling 17.3x and 18.6x; of the scalar
/// cycle on a 2,400-node CGAL block: 14.5x at nu 0.25, 6.9x at 0.45, 6.5x at 0.49
/// (docs/performance.md, item 21).
inline constexpr int kMinCoarsening = 10;

/// How the scalar cycle aggregates. `strong`: by the strong couplings alone, at every level
/// (the `multigrid` filter, whose cycle's extra mass is its lag: tenfold coarsening raised the
/// lag of the scaling ladder's structured meshes by 5-9 %, docs/performance.md item 21).
/// `tenfold`: a level that coarsens less than kMinCoarsening aggregates by every coupling
/// (implicit Euler's CG, where the cycle only preconditions: 1.5x faster at nu 0.49).
enum class Aggregates { strong, tenfold };

template <int dim> class SymmetricMultigrid {
public:
  explicit SymmetricMultigrid(const Eigen::SparseMatrix<double>& A, Eigen::Index coarsest = 64,
                              Aggregates aggregates = Aggregates::strong);

  /// x <- B b for each of the dim rows; b and x are dim x n (columns: A's rows) and distinct.
  void apply(const Nodal<dim>& b, Nodal<dim>& x);

  int levels() const { return static_cast<int>(m_levels.size()) + 1; }
  /// Rows of each level, finest first (the last is the one solved directly).
  std::vector<Eigen::Index> level_sizes() const;
  /// Bytes held by the matrices, prolongators, coarse factor and work arrays.
  std::size_t memory_bytes() const;

private:
  struct Csr {
    std::vector<int> ptr, col;
    std::vector<double> val;
  };
  struct Level {
    Csr lower, upper; ///< strictly lower and upper triangles of the level's A
    std::vector<double> inv_diag;
    Csr prolong; ///< P by fine rows: gathered to prolongate, scattered to restrict
  };
  /// Values per node in the cycle's work arrays: 3D nodes are padded to 4 lanes (the pad stays
  /// 0), so that each matrix entry updates a node with whole vector registers.
  static constexpr int kLanes = dim == 3 ? 4 : dim;
  using Lanes = Eigen::Matrix<double, kLanes, Eigen::Dynamic>;
  void cycle(std::size_t l, const double* b, double* x);

  std::vector<Level> m_levels;          ///< every level but the coarsest
  std::vector<Lanes> m_b, m_x;          ///< work: right-hand side and iterate per coarse level
  Lanes m_fine_b, m_fine_x;             ///< the finest level's, when kLanes != dim
  std::unique_ptr<NodalSolve> m_coarse; ///< the coarsest level's factor
  std::vector<int> m_coarse_order;      ///< coarsest row -> factor row
  Nodal<dim> m_coarse_rhs;              ///< the coarsest right-hand side in factor order
  Eigen::Index m_coarse_rows = 0;
  std::size_t m_coarse_bytes = 0;
};

} // namespace vtb
