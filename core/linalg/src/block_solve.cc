#include "vtb/linalg/block_solve.hh"
#include "vtb/linalg/vector_clones.hh"

#include "vtb/linalg/lanes.hh"

#include <algorithm>
#include <stdexcept>
#include <utility>

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
  // One value of padding: 3D reads a tile's last column as four values (tile_sum3).
  m_col_val.assign(ntiles * kTile + 1, 0.0);
  m_row_val.assign(ntiles * kTile + 1, 0.0);
  m_diag_val.resize(static_cast<std::size_t>(nb) * kTile);
  m_inv_diag.resize(L.cols());
  if (dim == 2) m_spread.assign(static_cast<std::size_t>(nb) * 4, 0.0);
  refresh();
}

template <int dim> void BlockSolve<dim>::refresh() {
  const double* val = m_factor.lower().valuePtr();
  const std::size_t n = m_col_row.size() * kTile;
  for (std::size_t k = 0; k < n; ++k) m_col_val[k] = m_source[k] >= 0 ? val[m_source[k]] : 0.0;
  for (std::size_t k = 0; k < m_diag_val.size(); ++k) m_diag_val[k] = m_source[n + k] >= 0 ? val[m_source[n + k]] : 0.0;
  for (std::size_t t = 0; t < m_row_tile.size(); ++t)
    std::copy_n(m_col_val.begin() + static_cast<std::ptrdiff_t>(m_row_tile[t]) * kTile, kTile,
                m_row_val.begin() + static_cast<std::ptrdiff_t>(t) * kTile);
  // The backward sweep multiplies by L_IJ^T: its tiles stored transposed (column-major L_IJ^T).
  for (std::size_t t = 0; t < m_col_row.size(); ++t) {
    Eigen::Map<Mat<dim>> tile(&m_col_val[t * kTile]);
    tile.transposeInPlace();
  }
  m_inv_diag = m_factor.diagonal().cwiseInverse();
  // Each node's unit lower tile L_II folded into its row's tiles (L_II^-1 L_IJ, for the
  // forward sweep) and its column's (L_JJ^-T L_IJ^T, for the backward sweep), so that a node's
  // values do not wait on each other through L_II in the sweeps (spread_solve,
  // solve_in_place in 3D): only the node's own b_I (known before its sum) meets L_II.
  for (int I = 0; I + 1 < static_cast<int>(m_row_ptr.size()); ++I) {
    const double* L = &m_diag_val[static_cast<std::size_t>(I) * kTile]; // L(p, q) = L[q dim + p]
    for (int t = m_row_ptr[static_cast<std::size_t>(I)]; t < m_row_ptr[static_cast<std::size_t>(I) + 1]; ++t)
      for (int c = 0; c < dim; ++c) {
        double* T = &m_row_val[static_cast<std::size_t>(t) * kTile + static_cast<std::size_t>(c * dim)];
        for (int p = 1; p < dim; ++p)
          for (int q = 0; q < p; ++q) T[p] -= L[q * dim + p] * T[q];
      }
  }
  for (int J = 0; J + 1 < static_cast<int>(m_col_ptr.size()); ++J) {
    const double* L = &m_diag_val[static_cast<std::size_t>(J) * kTile];
    for (int t = m_col_ptr[static_cast<std::size_t>(J)]; t < m_col_ptr[static_cast<std::size_t>(J) + 1]; ++t)
      for (int c = 0; c < dim; ++c) {
        double* T = &m_col_val[static_cast<std::size_t>(t) * kTile + static_cast<std::size_t>(c * dim)];
        for (int p = dim - 2; p >= 0; --p)
          for (int q = dim - 1; q > p; --q) T[p] -= L[p * dim + q] * T[q];
      }
  }
}

namespace {

/// sum over the tiles t in [begin, end) of tile_t * spread(col_t), each 2 x 2 tile
/// column-major (a, b, c, d) times the 2-vector (x, y) spread as (x, x, y, y): lanes (a x, b x,
/// c y, d y), whose halves add up to the product. One multiply and one add per tile where a
/// tile times a vector took two of each in a row: the sweeps are bound by the add's latency
/// (docs/performance.md). Two interleaved sums: two dependency chains of half the length.
[[gnu::always_inline]] inline detail::Lane<4> spread_tile_sum(int begin, int end, const double* __restrict val,
                                                              const int* __restrict col,
                                                              const double* __restrict spread) {
  using detail::load;
  detail::Lane<4> a = {0, 0, 0, 0}, b = a;
  int t = begin;
  for (; t + 1 < end; t += 2) {
    a += load<4>(val + 4 * t) * load<4>(spread + 4 * col[t]);
    b += load<4>(val + 4 * (t + 1)) * load<4>(spread + 4 * col[t + 1]);
  }
  if (t < end) a += load<4>(val + 4 * t) * load<4>(spread + 4 * col[t]);
  return a + b;
}

} // namespace

template <int dim>
template <class In, class Out>
[[gnu::always_inline]] inline void BlockSolve<dim>::spread_solve(int nb, In in, Out out) const {
  static_assert(dim == 2);
  // The nodes' values spread as (x, x, y, y) in m_spread for spread_tile_sum, written as each
  // node's value is found. The tiles hold the unit lower diagonal tiles [1 0; l 1] folded in
  // (refresh()): here only the node's own values meet l, known before the node's sum.
  double* __restrict S = m_spread.data();
  const double* D = m_diag_val.data(); // per node the unit lower tile's (1, 0) entry at D[4 I + 1]
  for (int I = 0; I < nb; ++I) {
    const auto [b0, b1] = in(I);
    const double c1 = b1 - D[4 * I + 1] * b0; // L_II^-1 b_I
    const detail::Lane<4> s =
        spread_tile_sum(m_row_ptr[static_cast<std::size_t>(I)], m_row_ptr[static_cast<std::size_t>(I) + 1],
                        m_row_val.data(), m_row_col.data(), S);
    const double r0 = b0 - (s[0] + s[2]);
    const double r1 = c1 - (s[1] + s[3]);
    detail::store<4>(S + 4 * I, detail::Lane<4>{r0, r0, r1, r1});
  }
  for (int J = nb - 1; J >= 0; --J) {
    const double z1 = m_inv_diag[2 * J + 1] * S[4 * J + 2];
    const double z0 = m_inv_diag[2 * J] * S[4 * J] - D[4 * J + 1] * z1; // L_JJ^-T D_J^-1 y_J
    const detail::Lane<4> s =
        spread_tile_sum(m_col_ptr[static_cast<std::size_t>(J)], m_col_ptr[static_cast<std::size_t>(J) + 1],
                        m_col_val.data(), m_col_row.data(), S);
    const double r1 = z1 - (s[1] + s[3]);
    const double r0 = z0 - (s[0] + s[2]);
    detail::store<4>(S + 4 * J, detail::Lane<4>{r0, r0, r1, r1});
    out(J, r0, r1);
  }
}

template <> VTB_VECTOR_CLONES void BlockSolve<2>::solve_in_place(Eigen::Ref<Nodal<2>> x) const {
  spread_solve(
      static_cast<int>(x.cols()),
      [&](int I) {
        return std::pair{x(0, I), x(1, I)};
      },
      [&](int J, double r0, double r1) {
        x(0, J) = r0;
        x(1, J) = r1;
      });
}

template <>
VTB_VECTOR_CLONES void BlockSolve<2>::solve_turned(const double* __restrict force, const double* __restrict turn,
                                                   const int* __restrict node, const int* __restrict slot, double scale,
                                                   double* __restrict y, double* __restrict out) const {
  // As TensorFilter::solve's loops did, operation for operation: R^T f = (c f0 + s f1, c f1 -
  // s f0) in, scale (c y0 - s y1, s y0 + c y1) out.
  spread_solve(
      static_cast<int>(m_inv_diag.size() / 2),
      [&](int I) {
        const int i = node[I];
        const double c = turn[2 * i], sn = turn[2 * i + 1], f0 = force[2 * i], f1 = force[2 * i + 1];
        return std::pair{c * f0 + sn * f1, -sn * f0 + c * f1};
      },
      [&](int J, double r0, double r1) {
        y[2 * J] = r0;
        y[2 * J + 1] = r1;
        if (!out) return;
        const int i = node[J], a = slot[J];
        const double c = turn[2 * i], sn = turn[2 * i + 1];
        out[2 * a] = scale * (c * r0 + -sn * r1);
        out[2 * a + 1] = scale * (sn * r0 + c * r1);
      });
}

namespace {

/// 3D: sum over the tiles t in [begin, end) of tile_t x(col_t), each 3 x 3 tile column-major:
/// its columns read as four values from offsets 0, 3 and 6 (the fourth lane is the next
/// column's, or the next tile's, or the padding: never used) times x's three values, in three
/// sums (one per column: three dependency chains of one add per tile).
[[gnu::always_inline]] inline detail::Lane<4> tile_sum3(int begin, int end, const double* __restrict val,
                                                        const int* __restrict col, const double* __restrict X,
                                                        Eigen::Index stride) {
  using detail::load;
  detail::Lane<4> a = {0, 0, 0, 0}, b = a, c = a;
  for (int t = begin; t < end; ++t) {
    const double* T = val + 9 * t;
    const double* x = X + stride * col[t];
    a += load<4>(T) * x[0];
    b += load<4>(T + 3) * x[1];
    c += load<4>(T + 6) * x[2];
  }
  return (a + b) + c;
}

} // namespace

template <> VTB_VECTOR_CLONES void BlockSolve<3>::solve_in_place(Eigen::Ref<Nodal<3>> x) const {
  const int nb = static_cast<int>(x.cols());
  const Eigen::Index st = x.outerStride();
  double* X = x.data();
  const double* L = m_diag_val.data(); // per node the unit lower tile, column-major: L(p, q) at 9 I + 3 q + p
  // Forward: y_I = L_II^-1 b_I - sum_J (L_II^-1 L_IJ) y_J (the tiles folded, refresh()).
  for (int I = 0; I < nb; ++I) {
    double* xi = X + st * I;
    const double* l = L + 9 * I;
    const double c0 = xi[0], c1 = xi[1] - l[1] * c0, c2 = xi[2] - l[2] * c0 - l[5] * c1;
    const detail::Lane<4> s =
        tile_sum3(m_row_ptr[static_cast<std::size_t>(I)], m_row_ptr[static_cast<std::size_t>(I) + 1], m_row_val.data(),
                  m_row_col.data(), X, st);
    xi[0] = c0 - s[0];
    xi[1] = c1 - s[1];
    xi[2] = c2 - s[2];
  }
  // Backward: x_J = L_JJ^-T D_J^-1 y_J - sum_I (L_JJ^-T L_IJ^T) x_I.
  for (int J = nb - 1; J >= 0; --J) {
    double* xj = X + st * J;
    const double* l = L + 9 * J;
    const double z0 = m_inv_diag[3 * J] * xj[0], z1 = m_inv_diag[3 * J + 1] * xj[1];
    const double w2 = m_inv_diag[3 * J + 2] * xj[2], w1 = z1 - l[5] * w2, w0 = z0 - l[1] * w1 - l[2] * w2;
    const detail::Lane<4> s =
        tile_sum3(m_col_ptr[static_cast<std::size_t>(J)], m_col_ptr[static_cast<std::size_t>(J) + 1], m_col_val.data(),
                  m_col_row.data(), X, st);
    xj[0] = w0 - s[0];
    xj[1] = w1 - s[1];
    xj[2] = w2 - s[2];
  }
}

template class BlockSolve<2>;
template class BlockSolve<3>;

} // namespace vtb
