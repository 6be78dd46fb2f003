#include "vtb/linalg/ordered_ldlt.hh"

#include <Eigen/OrderingMethods>
#include <algorithm>

namespace vtb {

OrderedLDLT::OrderedLDLT(const Eigen::SparseMatrix<double>& A) {
  const auto n = A.rows();
  // AMD returns the inverse permutation (as Eigen's own Cholesky uses it).
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> Pinv;
  Eigen::AMDOrdering<int>()(A, Pinv);
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P = Pinv.inverse();
  m_perm.assign(P.indices().data(), P.indices().data() + n);
  std::vector<Eigen::Triplet<double>> upper;
  upper.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) {
      const int r = ordered(static_cast<int>(it.row())), cc = ordered(static_cast<int>(it.col()));
      if (r <= cc) upper.emplace_back(r, cc, it.value());
    }
  m_upper.resize(n, n);
  m_upper.setFromTriplets(upper.begin(), upper.end());
  m_upper.makeCompressed();
  m_factor.analyzePattern(m_upper);
}

int OrderedLDLT::offset(int r, int c) const {
  if (r > c) std::swap(r, c);
  const int* inner = m_upper.innerIndexPtr();
  const int* first = inner + m_upper.outerIndexPtr()[c];
  const int* last = inner + m_upper.outerIndexPtr()[c + 1];
  const int* it = std::lower_bound(first, last, r);
  return (it != last && *it == r) ? static_cast<int>(it - inner) : -1;
}

bool OrderedLDLT::factorize() {
  m_factor.refactorize(m_upper);
  return m_factor.info() == Eigen::Success;
}

void OrderedLDLT::solve_in_place(Eigen::Ref<Eigen::MatrixXd> x) const {
  m_factor.matrixL().solveInPlace(x);
  x = m_factor.diagonal().cwiseInverse().asDiagonal() * x;
  m_factor.matrixU().solveInPlace(x);
}

} // namespace vtb
