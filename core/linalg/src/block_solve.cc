#include "vtb/linalg/block_solve.hh"
#include "vtb/linalg/vector_clones.hh"

#include <algorithm>
#include <stdexcept>

namespace vtb {

template <int dim> BlockSolve<dim>::BlockSolve(const OrderedLDLT& factor) : m_factor(factor) {
  const Eigen::SparseMatrix<double>& L = factor.lower();
  if (L.cols() % dim != 0) throw std::invalid_argument("BlockSolve: the factor's size is not a multiple of dim");
  const int nb = static_cast<int>(L.cols()) / dim;
  // Tile columns: the tile rows I > J that any of J's dim columns reaches.
  m_col_ptr.assign(1, 0);
  std::vector<int> rows;
  for (int J = 0; J < nb; ++J) {
    rows.clear();
    for (int q = 0; q < dim; ++q)
      for (Eigen::SparseMatrix<double>::InnerIterator it(L, J * dim + q); it; ++it)
        if (it.row() / dim > J) rows.push_back(static_cast<int>(it.row()) / dim);
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    m_col_row.insert(m_col_row.end(), rows.begin(), rows.end());
    m_col_ptr.push_back(static_cast<int>(m_col_row.size()));
  }
  const std::size_t ntiles = m_col_row.size();
  // Where each tile value comes from in L's value array; the diagonal tiles after the others.
  m_source.assign((ntiles + static_cast<std::size_t>(nb)) * kTile, -1);
  const int* outer = L.outerIndexPtr();
  const int* inner = L.innerIndexPtr();
  for (int J = 0; J < nb; ++J)
    for (int q = 0; q < dim; ++q)
      for (int k = outer[J * dim + q]; k < outer[J * dim + q + 1]; ++k) {
        const int i = inner[k], I = i / dim, p = i % dim;
        if (i <= J * dim + q) continue; // the stored diagonal, if any
        std::size_t slot;
        if (I == J) {
          slot = (ntiles + static_cast<std::size_t>(J)) * kTile;
        } else {
          const auto first = m_col_row.begin() + m_col_ptr[static_cast<std::size_t>(J)];
          const auto last = m_col_row.begin() + m_col_ptr[static_cast<std::size_t>(J) + 1];
          slot = static_cast<std::size_t>(std::lower_bound(first, last, I) - m_col_row.begin()) * kTile;
        }
        m_source[slot + static_cast<std::size_t>(q * dim + p)] = k; // column-major within the tile
      }
  // Tile rows: the transpose of the columns, columns ascending within a row.
  std::vector<int> count(static_cast<std::size_t>(nb) + 1, 0);
  for (int I : m_col_row) ++count[static_cast<std::size_t>(I) + 1];
  m_row_ptr.assign(static_cast<std::size_t>(nb) + 1, 0);
  for (int I = 0; I < nb; ++I)
    m_row_ptr[static_cast<std::size_t>(I) + 1] =
        m_row_ptr[static_cast<std::size_t>(I)] + count[static_cast<std::size_t>(I) + 1];
  m_row_col.resize(ntiles);
  m_row_tile.resize(ntiles);
  std::vector<int> next(m_row_ptr.begin(), m_row_ptr.end() - 1);
  for (int J = 0; J < nb; ++J)
    for (int t = m_col_ptr[static_cast<std::size_t>(J)]; t < m_col_ptr[static_cast<std::size_t>(J) + 1]; ++t) {
      const auto at =
          static_cast<std::size_t>(next[static_cast<std::size_t>(m_col_row[static_cast<std::size_t>(t)])]++);
      m_row_col[at] = J;
      m_row_tile[at] = t;
    }
  m_col_val.resize(ntiles * kTile);
  m_row_val.resize(ntiles * kTile);
  m_diag_val.resize(static_cast<std::size_t>(nb) * kTile);
  m_inv_diag.resize(L.cols());
  refresh();
}

template <int dim> void BlockSolve<dim>::refresh() {
  const double* val = m_factor.lower().valuePtr();
  const std::size_t n = m_col_val.size();
  for (std::size_t k = 0; k < n; ++k) m_col_val[k] = m_source[k] >= 0 ? val[m_source[k]] : 0.0;
  for (std::size_t k = 0; k < m_diag_val.size(); ++k) m_diag_val[k] = m_source[n + k] >= 0 ? val[m_source[n + k]] : 0.0;
  for (std::size_t t = 0; t < m_row_tile.size(); ++t)
    std::copy_n(m_col_val.begin() + static_cast<std::ptrdiff_t>(m_row_tile[t]) * kTile, kTile,
                m_row_val.begin() + static_cast<std::ptrdiff_t>(t) * kTile);
  m_inv_diag = m_factor.diagonal().cwiseInverse();
}

template <int dim> VTB_VECTOR_CLONES void BlockSolve<dim>::solve_in_place(Eigen::Ref<Nodal<dim>> x) const {
  using CMat = Eigen::Map<const Mat<dim>>;
  const int nb = static_cast<int>(x.cols());
  // Forward, L y = b by tile rows: r = b_I - sum_J L_IJ y_J, then the unit lower L_II.
  for (int I = 0; I < nb; ++I) {
    Vec<dim> a = Vec<dim>::Zero(), b = Vec<dim>::Zero(); // two chains: the sweep is latency bound
    int t = m_row_ptr[static_cast<std::size_t>(I)];
    const int end = m_row_ptr[static_cast<std::size_t>(I) + 1];
    for (; t + 1 < end; t += 2) {
      a.noalias() +=
          CMat(&m_row_val[static_cast<std::size_t>(t) * kTile]) * x.col(m_row_col[static_cast<std::size_t>(t)]);
      b.noalias() +=
          CMat(&m_row_val[static_cast<std::size_t>(t + 1) * kTile]) * x.col(m_row_col[static_cast<std::size_t>(t) + 1]);
    }
    if (t < end)
      a.noalias() +=
          CMat(&m_row_val[static_cast<std::size_t>(t) * kTile]) * x.col(m_row_col[static_cast<std::size_t>(t)]);
    // Scalars, not a Vec: a Vec's elements went through the stack, and writing one of them
    // and then reading the whole stalled store forwarding (a third of the solve's time).
    double r[dim];
    const double* D = &m_diag_val[static_cast<std::size_t>(I) * kTile]; // column-major
    for (int p = 0; p < dim; ++p) {
      r[p] = x(p, I) - a[p] - b[p];
      for (int q = 0; q < p; ++q) r[p] -= D[q * dim + p] * r[q];
    }
    for (int p = 0; p < dim; ++p) x(p, I) = r[p];
  }
  // Backward, L^T x = D^-1 y by tile columns: r = D_J^-1 y_J - sum_I L_IJ^T x_I, then L_JJ^T.
  for (int J = nb - 1; J >= 0; --J) {
    Vec<dim> a = Vec<dim>::Zero(), b = Vec<dim>::Zero();
    int t = m_col_ptr[static_cast<std::size_t>(J)];
    const int end = m_col_ptr[static_cast<std::size_t>(J) + 1];
    for (; t + 1 < end; t += 2) {
      a.noalias() += CMat(&m_col_val[static_cast<std::size_t>(t) * kTile]).transpose() *
                     x.col(m_col_row[static_cast<std::size_t>(t)]);
      b.noalias() += CMat(&m_col_val[static_cast<std::size_t>(t + 1) * kTile]).transpose() *
                     x.col(m_col_row[static_cast<std::size_t>(t) + 1]);
    }
    if (t < end)
      a.noalias() += CMat(&m_col_val[static_cast<std::size_t>(t) * kTile]).transpose() *
                     x.col(m_col_row[static_cast<std::size_t>(t)]);
    double r[dim];
    const double* D = &m_diag_val[static_cast<std::size_t>(J) * kTile];
    for (int q = dim - 1; q >= 0; --q) {
      r[q] = m_inv_diag[J * dim + q] * x(q, J) - a[q] - b[q];
      for (int p = q + 1; p < dim; ++p) r[q] -= D[q * dim + p] * r[p];
    }
    for (int q = 0; q < dim; ++q) x(q, J) = r[q];
  }
}

template class BlockSolve<2>;
template class BlockSolve<3>;

} // namespace vtb
