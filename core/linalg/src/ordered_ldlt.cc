#include "vtb/linalg/ordered_ldlt.hh"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <stdexcept>

namespace vtb {

namespace {

/// The pattern of A's block x block tiles (a tile with any entry is one entry).
Eigen::SparseMatrix<double> block_graph(const Eigen::SparseMatrix<double>& A, int block) {
  std::vector<Eigen::Triplet<double>> tiles;
  tiles.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it)
      tiles.emplace_back(static_cast<int>(it.row()) / block, c / block, 1.0);
  Eigen::SparseMatrix<double> G(A.rows() / block, A.cols() / block);
  G.setFromTriplets(tiles.begin(), tiles.end());
  return G;
}

} // namespace

OrderedLDLT::OrderedLDLT(const Eigen::SparseMatrix<double>& A, int block) {
  const auto n = A.rows();
  if (block < 1 || n % block != 0) throw std::invalid_argument("OrderedLDLT: rows not a multiple of the block");
  // AMD returns the inverse permutation (as Eigen's own Cholesky uses it).
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> Pinv;
  if (block == 1) {
    Eigen::AMDOrdering<int>()(A, Pinv);
  } else {
    Eigen::AMDOrdering<int>()(block_graph(A, block), Pinv);
  }
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P = Pinv.inverse();
  m_perm.resize(static_cast<std::size_t>(n));
  for (Eigen::Index r = 0; r < n; ++r)
    m_perm[static_cast<std::size_t>(r)] = P.indices()[r / block] * block + static_cast<int>(r % block);
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
