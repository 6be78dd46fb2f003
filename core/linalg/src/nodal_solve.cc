#include "vtb/linalg/nodal_solve.hh"
#include "vtb/linalg/vector_clones.hh"

namespace vtb {

namespace {

/// sum over p in [begin, end) of val[p] x(col[p]), in two interleaved sums: each row's
/// terms then form two dependency chains of half the length (the sweeps are latency bound).
template <int dim>
[[gnu::always_inline]] inline Vec<dim> dot_row(int begin, int end, const std::vector<double>& val,
                                               const std::vector<int>& col, const double* X) {
  Vec<dim> a = Vec<dim>::Zero(), b = Vec<dim>::Zero();
  int p = begin;
  for (; p + 1 < end; p += 2) {
    a += val[static_cast<std::size_t>(p)] * Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p)] * dim);
    b += val[static_cast<std::size_t>(p) + 1] *
         Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p) + 1] * dim);
  }
  if (p < end)
    a += val[static_cast<std::size_t>(p)] * Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p)] * dim);
  return a + b;
}

} // namespace

NodalSolve::NodalSolve(const OrderedLDLT& factor) {
  const Eigen::SparseMatrix<double>& L = factor.lower();
  const auto n = static_cast<std::size_t>(L.cols());
  m_inv_diag = factor.diagonal().cwiseInverse();
  // By columns: L as Eigen stores it, without a diagonal entry if one is stored.
  m_col_ptr.assign(1, 0);
  std::vector<int> row_count(n, 0);
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, j); it; ++it)
      if (it.row() > j) {
        m_col_row.push_back(static_cast<int>(it.row()));
        m_col_val.push_back(it.value());
        ++row_count[static_cast<std::size_t>(it.row())];
      }
    m_col_ptr.push_back(static_cast<int>(m_col_row.size()));
  }
  // By rows: the transpose, columns ascending within a row.
  m_row_ptr.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) m_row_ptr[i + 1] = m_row_ptr[i] + row_count[i];
  m_row_col.resize(m_col_row.size());
  m_row_val.resize(m_col_val.size());
  std::vector<int> next(m_row_ptr.begin(), m_row_ptr.end() - 1);
  for (std::size_t j = 0; j < n; ++j)
    for (int p = m_col_ptr[j]; p < m_col_ptr[j + 1]; ++p) {
      const auto at =
          static_cast<std::size_t>(next[static_cast<std::size_t>(m_col_row[static_cast<std::size_t>(p)])]++);
      m_row_col[at] = static_cast<int>(j);
      m_row_val[at] = m_col_val[static_cast<std::size_t>(p)];
    }
}

template <int dim>
VTB_VECTOR_CLONES void NodalSolve::solve_gathered(const Nodal<dim>& b, const int* source, Nodal<dim>& x) const {
  const auto n = static_cast<int>(m_inv_diag.size());
  double* X = x.data();
  const double* B = b.data();
  // Forward: y_i = b_i - sum_{j < i} L_ij y_j (L by rows).
  for (int i = 0; i < n; ++i) {
    const Vec<dim> sum = dot_row<dim>(m_row_ptr[static_cast<std::size_t>(i)],
                                      m_row_ptr[static_cast<std::size_t>(i) + 1], m_row_val, m_row_col, X);
    Eigen::Map<Vec<dim>>(X + i * dim) = Eigen::Map<const Vec<dim>>(B + (source ? source[i] : i) * dim) - sum;
  }
  // Diagonal and backward: x_j = y_j / d_j - sum_{i > j} L_ij x_i (L by columns).
  for (int j = n - 1; j >= 0; --j) {
    const Vec<dim> sum = dot_row<dim>(m_col_ptr[static_cast<std::size_t>(j)],
                                      m_col_ptr[static_cast<std::size_t>(j) + 1], m_col_val, m_col_row, X);
    Eigen::Map<Vec<dim>> xj(X + j * dim);
    xj = m_inv_diag[j] * xj - sum;
  }
}

// Built for AVX2 too (vector_clones.hh): the sweeps are bound by latency, and the AVX2 build's
// three-operand instructions need fewer register copies on the critical path.
template void NodalSolve::solve_gathered<1>(const Nodal<1>&, const int*, Nodal<1>&) const;
template void NodalSolve::solve_gathered<2>(const Nodal<2>&, const int*, Nodal<2>&) const;
template void NodalSolve::solve_gathered<3>(const Nodal<3>&, const int*, Nodal<3>&) const;

} // namespace vtb
