#pragma once
/// \file
/// A sparse LDL^T (Eigen's SimplicialLDLT, AMD ordering) solved for many right-hand sides in
/// one sweep of the factor. Eigen's sparse triangular solve sweeps L once per right-hand side;
/// with k of them (the spring fit solves 16 to 30 at once) the sweeps are latency bound and
/// read L k times. Here L is kept by rows (forward sweep) and by columns (backward sweep) and
/// the right-hand sides are stored row-major, so that each entry of L updates k contiguous
/// values (docs/fidelity.md measures the fit with it).

#include <Eigen/Core>
#include <Eigen/SparseCholesky>

namespace vtb {

class BatchedLDLT {
public:
  /// Factorises the symmetric positive definite A (both triangles stored); the ordering is
  /// computed at the first call and kept (later matrices must have the same pattern). False
  /// if A is not positive definite.
  bool factorize(const Eigen::SparseMatrix<double>& A);

  /// X = A^-1 B, column by column.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;

private:
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> m_ldlt;
  bool m_analysed = false;
  Eigen::SparseMatrix<double, Eigen::RowMajor> m_rows; ///< L by rows (strictly lower)
  Eigen::SparseMatrix<double> m_cols;                  ///< L by columns (strictly lower)
  Eigen::VectorXd m_inv_diag;
  Eigen::VectorXi m_perm; ///< ordered row of original row i
};

} // namespace vtb
