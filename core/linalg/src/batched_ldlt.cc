#include "vtb/linalg/batched_ldlt.hh"

#include "vtb/linalg/vector_clones.hh"

namespace vtb {
namespace {

/// y -= l x over k values (y and x are distinct rows).
inline void axpy(double* __restrict y, const double* __restrict x, double l, Eigen::Index k) {
  for (Eigen::Index c = 0; c < k; ++c) y[c] -= l * x[c];
}

/// The forward sweep L y = y (L by rows), the diagonal and the backward sweep L^T x = D^-1 y
/// (L by columns), in place on the row-major n x k y.
VTB_VECTOR_CLONES void sweeps(const Eigen::SparseMatrix<double, Eigen::RowMajor>& rows,
                              const Eigen::SparseMatrix<double>& cols, const Eigen::VectorXd& inv_diag, double* y,
                              Eigen::Index k) {
  const Eigen::Index n = inv_diag.size();
  // Forward: y_i -= sum_{j < i} L_ij y_j over row i of L.
  for (Eigen::Index i = 0; i < n; ++i) {
    double* yi = y + i * k;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(rows, i); it; ++it)
      axpy(yi, y + it.col() * k, it.value(), k);
  }
  // Diagonal and backward: x_j = y_j / d_j - sum_{i > j} L_ij x_i over column j.
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    double* xj = y + j * k;
    const double d = inv_diag[j];
    for (Eigen::Index c = 0; c < k; ++c) xj[c] *= d;
    for (Eigen::SparseMatrix<double>::InnerIterator it(cols, j); it; ++it) axpy(xj, y + it.row() * k, it.value(), k);
  }
}

} // namespace

bool BatchedLDLT::factorize(const Eigen::SparseMatrix<double>& A) {
  if (!m_analysed) m_ldlt.analyzePattern(A), m_analysed = true;
  m_ldlt.factorize(A);
  if (m_ldlt.info() != Eigen::Success) return false;
  // matrixL() is unit lower: its stored part is the strict lower triangle.
  m_cols = m_ldlt.matrixL().nestedExpression();
  m_rows = m_cols;
  m_inv_diag = m_ldlt.vectorD().cwiseInverse();
  m_perm = m_ldlt.permutationP().indices();
  return (m_ldlt.vectorD().array() > 0).all();
}

Eigen::MatrixXd BatchedLDLT::solve(const Eigen::MatrixXd& B) const {
  const Eigen::Index n = B.rows(), k = B.cols();
  RowMatrix Y(n, k);
  for (Eigen::Index i = 0; i < n; ++i) Y.row(m_perm[i]) = B.row(i); // Y = P B
  sweeps(m_rows, m_cols, m_inv_diag, Y.data(), k);
  Eigen::MatrixXd X(n, k);
  for (Eigen::Index i = 0; i < n; ++i) X.row(i) = Y.row(m_perm[i]); // X = P^-1 Y
  return X;
}

} // namespace vtb
