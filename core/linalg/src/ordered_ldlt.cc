#include "vtb/linalg/ordered_ldlt.hh"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <functional>
#include <queue>
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

/// The upper triangle of A's pattern under the ordering `perm` (original row -> ordered row).
Eigen::SparseMatrix<double> ordered_upper(const Eigen::SparseMatrix<double>& A, const std::vector<int>& perm) {
  std::vector<Eigen::Triplet<double>> upper;
  upper.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) {
      const int r = perm[static_cast<std::size_t>(it.row())], cc = perm[static_cast<std::size_t>(it.col())];
      if (r <= cc) upper.emplace_back(r, cc, it.value());
    }
  Eigen::SparseMatrix<double> U(A.rows(), A.cols());
  U.setFromTriplets(upper.begin(), upper.end());
  U.makeCompressed();
  return U;
}

} // namespace

std::vector<int> interleaved_order(const int* parent, int n) {
  std::vector<int> pending(static_cast<std::size_t>(n), 0); // children not yet listed
  for (int i = 0; i < n; ++i)
    if (parent[i] >= 0) ++pending[static_cast<std::size_t>(parent[i])];
  std::priority_queue<int, std::vector<int>, std::greater<>> ready; // smallest given position first
  for (int i = 0; i < n; ++i)
    if (pending[static_cast<std::size_t>(i)] == 0) ready.push(i);
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(n));
  int last = -1;
  while (!ready.empty()) {
    int pick = ready.top();
    ready.pop();
    if (last >= 0 && pick == parent[last] && !ready.empty()) { // it would wait on the row just listed
      const int other = ready.top();
      ready.pop();
      ready.push(pick);
      pick = other;
    }
    order.push_back(pick);
    last = pick;
    if (parent[pick] >= 0 && --pending[static_cast<std::size_t>(parent[pick])] == 0) ready.push(parent[pick]);
  }
  return order;
}

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
  // AMD's order of the blocks, then interleaved on the blocks' elimination tree.
  const auto nb = static_cast<int>(n / block);
  std::vector<int> amd(static_cast<std::size_t>(nb));
  for (int b = 0; b < nb; ++b) amd[static_cast<std::size_t>(b)] = P.indices()[b];
  Factor tree;
  tree.analyzePattern(ordered_upper(block == 1 ? A : block_graph(A, block), amd));
  const std::vector<int> order = interleaved_order(tree.parent(), nb); // order[k]: AMD position listed k-th
  std::vector<int> position(static_cast<std::size_t>(nb));
  for (int k = 0; k < nb; ++k) position[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
  m_perm.resize(static_cast<std::size_t>(n));
  for (Eigen::Index r = 0; r < n; ++r)
    m_perm[static_cast<std::size_t>(r)] =
        position[static_cast<std::size_t>(amd[static_cast<std::size_t>(r / block)])] * block +
        static_cast<int>(r % block);
  m_upper = ordered_upper(A, m_perm);
  m_factor.analyzePattern(m_upper);
  m_y.assign(static_cast<std::size_t>(n), 0.0);
  m_pattern.assign(static_cast<std::size_t>(n), 0);
  m_tags.assign(static_cast<std::size_t>(n), 0);
  m_factor.size_diagonal();
}

double OrderedLDLT::Factor::rows(const Eigen::SparseMatrix<double>& ap, int k, int end, std::vector<double>& y,
                                 std::vector<int>& pattern, std::vector<int>& tags) {
  // Eigen's SimplicialCholeskyBase::factorize_preordered (LDL^T, no shift), its loop over rows
  // k .. end - 1.
  const int size = static_cast<int>(ap.rows());
  const int* Lp = this->m_matrix.outerIndexPtr();
  int* Li = this->m_matrix.innerIndexPtr();
  double* Lx = this->m_matrix.valuePtr();
  int* nz = this->m_nonZerosPerCol.data();
  const int* parent = this->m_parent.data();
  double* diag = this->m_diag.data();
  double work = 0;
  for (; k < end; ++k) {
    y[static_cast<std::size_t>(k)] = 0;
    int top = size;
    tags[static_cast<std::size_t>(k)] = k;
    nz[k] = 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(ap, k); it; ++it) {
      int i = static_cast<int>(it.index());
      if (i <= k) {
        y[static_cast<std::size_t>(i)] += it.value();
        int len = 0;
        for (; tags[static_cast<std::size_t>(i)] != k; i = parent[i]) {
          pattern[static_cast<std::size_t>(len++)] = i;
          tags[static_cast<std::size_t>(i)] = k;
        }
        while (len > 0) pattern[static_cast<std::size_t>(--top)] = pattern[static_cast<std::size_t>(--len)];
      }
    }
    double d = y[static_cast<std::size_t>(k)] * this->m_shiftScale + this->m_shiftOffset;
    y[static_cast<std::size_t>(k)] = 0;
    for (; top < size; ++top) {
      const int i = pattern[static_cast<std::size_t>(top)];
      const double yi = y[static_cast<std::size_t>(i)];
      y[static_cast<std::size_t>(i)] = 0;
      const double l_ki = yi / diag[i];
      const int p2 = Lp[i] + nz[i];
      int p;
      for (p = Lp[i]; p < p2; ++p) y[static_cast<std::size_t>(Li[p])] -= Lx[p] * yi;
      work += p2 - Lp[i] + 1;
      d -= l_ki * yi;
      Li[p] = k;
      Lx[p] = l_ki;
      ++nz[i];
    }
    diag[k] = d;
    if (d == 0) return -1;
  }
  return work;
}

void OrderedLDLT::begin_factorize() {
  m_part_row = 0;
  m_part_ok = true;
}

bool OrderedLDLT::factorize_part(double work) {
  const int n = static_cast<int>(m_upper.rows());
  double done = 0;
  while (m_part_row < n && m_part_ok && (done < work || done == 0)) {
    const double w = m_factor.rows(m_upper, m_part_row, m_part_row + 1, m_y, m_pattern, m_tags);
    ++m_part_row;
    m_part_ok = w >= 0;
    done += w + 1;
  }
  if (m_part_row < n && m_part_ok) return false;
  m_factor.finish(m_part_ok);
  return true;
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
  // factorize_part's loop over every row at once, counting the whole factorisation's work.
  begin_factorize();
  const double w = m_factor.rows(m_upper, 0, static_cast<int>(m_upper.rows()), m_y, m_pattern, m_tags);
  m_part_ok = w >= 0;
  if (m_part_ok) m_work = w + static_cast<double>(m_upper.rows());
  m_factor.finish(m_part_ok);
  return m_part_ok;
}

void OrderedLDLT::solve_in_place(Eigen::Ref<Eigen::MatrixXd> x) const {
  m_factor.matrixL().solveInPlace(x);
  x = m_factor.diagonal().cwiseInverse().asDiagonal() * x;
  m_factor.matrixU().solveInPlace(x);
}

} // namespace vtb
