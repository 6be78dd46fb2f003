#include "vtb/linalg/selected_inverse.hh"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <stdexcept>

namespace vtb {

Eigen::SparseMatrix<double> selected_inverse(const Eigen::SparseMatrix<double>& A) {
  using SpMat = Eigen::SparseMatrix<double>;
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt(A);
  if (ldlt.info() != Eigen::Success) throw std::runtime_error("selected_inverse: matrix is not positive definite");
  const SpMat& L = ldlt.matrixL().nestedExpression(); // strictly lower, unit diagonal implied
  const Eigen::VectorXd d = ldlt.vectorD();
  const int n = static_cast<int>(A.rows());
  const int* Lp = L.outerIndexPtr();
  const int* Li = L.innerIndexPtr();
  const double* Lx = L.valuePtr();
  std::vector<double> Zx(static_cast<std::size_t>(L.nonZeros()), 0.0), Zd(static_cast<std::size_t>(n), 0.0);

  // Z(i, k) for i, k > j: both are in the filled pattern (the rows of a column of L form a clique).
  auto z = [&](int i, int k) -> double {
    if (i == k) return Zd[static_cast<std::size_t>(i)];
    const int a = std::min(i, k), b = std::max(i, k);
    const int* first = Li + Lp[a];
    const int* last = Li + Lp[a + 1];
    const int* it = std::lower_bound(first, last, b);
    return Zx[static_cast<std::size_t>(it - Li)];
  };
  for (int j = n - 1; j >= 0; --j) {
    for (int p = Lp[j]; p < Lp[j + 1]; ++p) {
      const int i = Li[p];
      double s = 0;
      for (int q = Lp[j]; q < Lp[j + 1]; ++q) s += z(i, Li[q]) * Lx[q];
      Zx[static_cast<std::size_t>(p)] = -s;
    }
    double s = 0;
    for (int q = Lp[j]; q < Lp[j + 1]; ++q) s += Lx[q] * Zx[static_cast<std::size_t>(q)];
    Zd[static_cast<std::size_t>(j)] = 1.0 / d[j] - s;
  }

  // Back to A's numbering: A^-1(r, c) = Z(p[r], p[c]).
  const auto& perm = ldlt.permutationP().indices();
  SpMat out = A;
  for (int c = 0; c < out.outerSize(); ++c)
    for (SpMat::InnerIterator it(out, c); it; ++it) it.valueRef() = z(perm[it.row()], perm[it.col()]);
  return out;
}

} // namespace vtb
