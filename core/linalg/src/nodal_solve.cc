#include "vtb/linalg/nodal_solve.hh"

namespace vtb {

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

} // namespace vtb
