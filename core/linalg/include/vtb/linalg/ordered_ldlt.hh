#pragma once
/// \file
/// A sparse LDL^T for matrices of fixed pattern: ordered once (AMD, then interleaved: below),
/// then factorised and solved without allocating, which the time step requires. Wraps Eigen's
/// SimplicialLDLT: its symbolic analysis, factor storage and solves; the numeric factorisation
/// is its up-looking loop (factorize_preordered) restated so that it can stop after any row
/// and resume (factorize_part), which Eigen's cannot.
///
/// The triangular sweeps of a small factor are bound by latency: a row that needs the row just
/// solved waits for it, where two rows that do not need each other overlap. So AMD's order is
/// rearranged (interleaved_order) so that a row rarely follows its elimination-tree child: any
/// order that lists each node after its children has the same fill (docs/performance.md).

#include <Eigen/SparseCholesky>

#include <vector>

namespace vtb {

/// A topological order of the elimination tree `parent` (-1 at a root) over n nodes: the
/// nodes ready (their children listed) in their given order, except that a node does not come
/// right after its own child while another node is ready.
std::vector<int> interleaved_order(const int* parent, int n);

class OrderedLDLT {
public:
  /// Takes the pattern (and values) of a symmetric matrix with both triangles stored.
  /// block > 1: rows come in blocks of `block` (a node's coordinates, row block a + p); AMD
  /// orders the blocks' graph and each block's rows stay consecutive and in their order, so
  /// that L is made of block x block tiles (BlockSolve).
  explicit OrderedLDLT(const Eigen::SparseMatrix<double>& A, int block = 1);

  /// Row of the ordered matrix that holds original row i.
  int ordered(int i) const { return m_perm[static_cast<std::size_t>(i)]; }
  /// Offset into values() of the ordered entry (r, c), r and c already ordered, any triangle.
  int offset(int r, int c) const;
  /// The ordered upper triangle's values, to be filled before factorize().
  double* values() { return m_upper.valuePtr(); }
  Eigen::Index nonzeros() const { return m_upper.nonZeros(); }
  Eigen::Index size() const { return m_upper.rows(); }

  /// Numeric factorisation of the current values; false if not positive definite.
  bool factorize();
  /// The same factorisation in parts, so that a time step can carry a share of it (a bounded
  /// step, tensor_filter.hh): begin_factorize(), then factorize_part(work) until it returns
  /// true, each call taking rows of L until about `work` multiply-adds are done (at least one
  /// row); factorized() then says what factorize() would have returned. The arithmetic is
  /// factorize()'s, row by row (Eigen's up-looking LDL^T), so the factor is the same to the
  /// bit. The factor must not be solved with in between. Allocates nothing.
  void begin_factorize();
  bool factorize_part(double work);
  bool factorized() const { return m_part_ok; }
  /// The multiply-adds (and rows) of one whole factorisation, counted by the last factorize()
  /// (0 before): what factorize_part's `work` is a share of.
  double factorize_work() const { return m_work; }
  /// Solves in place for right-hand sides given in the ordered numbering.
  void solve_in_place(Eigen::Ref<Eigen::MatrixXd> x) const;
  /// The factor L (unit lower, columns) and D of A = L D L^T in the ordered numbering.
  const Eigen::SparseMatrix<double>& lower() const { return m_factor.lower(); }
  const Eigen::VectorXd& diagonal() const { return m_factor.diagonal(); }

private:
  class Factor : public Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>> {
  public:
    /// D's storage, sized once after analyzePattern (rows() writes into it).
    void size_diagonal() { this->m_diag.resize(this->m_parent.size()); }
    /// D of L D L^T by reference (vectorD() returns a copy).
    const Eigen::VectorXd& diagonal() const { return this->m_diag; }
    const Eigen::SparseMatrix<double>& lower() const { return this->m_matrix; }
    /// The elimination tree after analyzePattern: each column's parent, -1 at a root.
    const int* parent() const { return this->m_parent.data(); }
    /// factorize_preordered's loop for rows [k, end), with its scratch (y, pattern, tags)
    /// kept between calls; returns the multiply-adds done, or -1 at a zero pivot.
    double rows(const Eigen::SparseMatrix<double>& upper, int k, int end, std::vector<double>& y,
                std::vector<int>& pattern, std::vector<int>& tags);
    /// The factor's state after the last row: Success, or NumericalIssue at a zero pivot.
    void finish(bool ok) {
      this->m_info = ok ? Eigen::Success : Eigen::NumericalIssue;
      this->m_factorizationIsOk = true;
    }
  };
  std::vector<int> m_perm;
  Eigen::SparseMatrix<double> m_upper;
  Factor m_factor;
  // factorize_part's state: the next row, whether every row so far had a pivot, the scratch,
  // and the whole factorisation's multiply-adds.
  int m_part_row = 0;
  bool m_part_ok = false;
  std::vector<double> m_y;
  std::vector<int> m_pattern, m_tags;
  double m_work = 0;
};

} // namespace vtb
