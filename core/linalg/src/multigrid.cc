#include "vtb/linalg/multigrid.hh"
#include "aggregation.hh"
#include "vtb/linalg/lanes.hh"
#include "vtb/linalg/ordered_ldlt.hh"

#include "vtb/linalg/vector_clones.hh"

#include <cmath>
#include <stdexcept>

namespace vtb {

namespace {

using detail::Lane;
using detail::load;
using detail::RowSparse;
using detail::store;

template <class Sparse>
void to_csr(const Sparse& S, std::vector<int>& ptr, std::vector<int>& col, std::vector<double>& val,
            int keep /* -1 lower, 0 all, 1 upper */) {
  const RowSparse R(S);
  ptr.assign(1, 0);
  col.clear();
  val.clear();
  for (Eigen::Index i = 0; i < R.outerSize(); ++i) {
    for (RowSparse::InnerIterator it(R, i); it; ++it)
      if (keep == 0 || (keep < 0 && it.col() < i) || (keep > 0 && it.col() > i)) {
        col.push_back(static_cast<int>(it.col()));
        val.push_back(it.value());
      }
    ptr.push_back(static_cast<int>(col.size()));
  }
}

/// One level's matrices as raw arrays, for the sweeps below.
struct LevelArrays {
  const int *lp, *lc, *up, *uc, *pp, *pc;
  const double *lv, *uv, *pv, *dinv;
  int n;
};

// The level's sweeps on nodes of W lanes (x of node i at x[i W .. i W + W)), one GCC vector
// per node (lanes.hh), so that each matrix entry updates a node with whole vector registers:
// for 4 lanes, two SSE2 operations in the baseline build and one AVX2 operation in the clones
// below (always inlined into them). Lane by lane the operations are those of the scalar
// sweeps, in the same order.

/// s -= sum over p in [begin, end) of val[p] x(col[p]), term by term: one row's part of a sweep.
template <int W>
[[gnu::always_inline]] inline void subtract_row(Lane<W>& s, int begin, int end, const int* col, const double* val,
                                                const double* x) {
  for (int p = begin; p < end; ++p) s -= val[p] * load<W>(x + col[p] * W);
}

/// Forward Gauss-Seidel from x = 0 (only the lower triangle meets nonzero x), then the
/// restricted residual bc = P^T (b - A x) = P^T (-U x) (the diagonal and lower parts cancel b
/// exactly after that sweep), with the fine residual formed row by row; bc is zeroed here.
template <int W>
[[gnu::always_inline]] inline void presmooth_and_restrict(const LevelArrays& L, int nc, const double* b, double* x,
                                                          double* bc) {
  const int *lp = L.lp, *lc = L.lc, *up = L.up, *uc = L.uc, *pp = L.pp, *pc = L.pc;
  const double *lv = L.lv, *uv = L.uv, *pv = L.pv, *dinv = L.dinv;
  const int n = L.n;
  for (int i = 0; i < n; ++i) {
    Lane<W> s = load<W>(b + i * W);
    subtract_row<W>(s, lp[i], lp[i + 1], lc, lv, x);
    store<W>(x + i * W, dinv[i] * s);
  }
  for (int c = 0; c < nc * W; ++c) bc[c] = 0;
  for (int i = 0; i < n; ++i) {
    Lane<W> r = {};
    subtract_row<W>(r, up[i], up[i + 1], uc, uv, x);
    for (int p = pp[i]; p < pp[i + 1]; ++p) store<W>(bc + pc[p] * W, load<W>(bc + pc[p] * W) + pv[p] * r);
  }
}

/// x += P xc (gathered by P's rows), then backward Gauss-Seidel with the whole matrix.
template <int W>
[[gnu::always_inline]] inline void prolongate_and_postsmooth(const LevelArrays& L, const double* xc, const double* b,
                                                             double* x) {
  const int *lp = L.lp, *lc = L.lc, *up = L.up, *uc = L.uc, *pp = L.pp, *pc = L.pc;
  const double *lv = L.lv, *uv = L.uv, *pv = L.pv, *dinv = L.dinv;
  const int n = L.n;
  for (int i = 0; i < n; ++i) {
    Lane<W> s = load<W>(x + i * W);
    for (int p = pp[i]; p < pp[i + 1]; ++p) s += pv[p] * load<W>(xc + pc[p] * W);
    store<W>(x + i * W, s);
  }
  for (int i = n - 1; i >= 0; --i) {
    Lane<W> s = load<W>(b + i * W);
    Lane<W> t = {}; // two sums, so that the row's subtractions form two shorter chains
    subtract_row<W>(s, lp[i], lp[i + 1], lc, lv, x);
    subtract_row<W>(t, up[i], up[i + 1], uc, uv, x);
    store<W>(x + i * W, dinv[i] * (s + t));
  }
}

// The 4-lane (3D) sweeps, built for AVX-512F, AVX2 and the baseline (vector_clones.hh).
VTB_VECTOR_CLONES_WIDE void presmooth_and_restrict4(const LevelArrays& L, int nc, const double* b, double* x,
                                                    double* bc) {
  presmooth_and_restrict<4>(L, nc, b, x, bc);
}
VTB_VECTOR_CLONES_WIDE void prolongate_and_postsmooth4(const LevelArrays& L, const double* xc, const double* b,
                                                       double* x) {
  prolongate_and_postsmooth<4>(L, xc, b, x);
}

template <int W> void presmooth_and_restrict_any(const LevelArrays& L, int nc, const double* b, double* x, double* bc) {
  if constexpr (W == 4)
    presmooth_and_restrict4(L, nc, b, x, bc);
  else
    presmooth_and_restrict<W>(L, nc, b, x, bc);
}
template <int W>
void prolongate_and_postsmooth_any(const LevelArrays& L, const double* xc, const double* b, double* x) {
  if constexpr (W == 4)
    prolongate_and_postsmooth4(L, xc, b, x);
  else
    prolongate_and_postsmooth<W>(L, xc, b, x);
}

} // namespace

template <int dim>
SymmetricMultigrid<dim>::SymmetricMultigrid(const Eigen::SparseMatrix<double>& A0, Eigen::Index coarsest,
                                            Aggregates aggregates) {
  RowSparse A(A0);
  if constexpr (kLanes != dim) {
    m_fine_b = Lanes::Zero(kLanes, A.rows());
    m_fine_x = Lanes::Zero(kLanes, A.rows());
  }
  std::vector<int> agg;
  while (A.rows() > coarsest) {
    const int nc = aggregates == Aggregates::tenfold ? detail::aggregate_tenfold(A, agg) : detail::aggregate(A, agg);
    if (nc >= A.rows()) break; // nothing to coarsen (no off-diagonal couplings)
    const RowSparse P = detail::smoothed_prolongator(A, agg, nc);
    const RowSparse R = P.transpose();
    Level lev;
    to_csr(A, lev.lower.ptr, lev.lower.col, lev.lower.val, -1);
    to_csr(A, lev.upper.ptr, lev.upper.col, lev.upper.val, 1);
    lev.inv_diag.resize(static_cast<std::size_t>(A.rows()));
    for (Eigen::Index i = 0; i < A.rows(); ++i) lev.inv_diag[static_cast<std::size_t>(i)] = 1.0 / A.coeff(i, i);
    to_csr(P, lev.prolong.ptr, lev.prolong.col, lev.prolong.val, 0);
    m_levels.push_back(std::move(lev));
    RowSparse coarse = R * A * P;
    coarse.prune(0.0);
    A = coarse;
    m_b.emplace_back(Lanes::Zero(kLanes, A.rows()));
    m_x.emplace_back(Lanes::Zero(kLanes, A.rows()));
  }
  const Eigen::SparseMatrix<double> Ac(A);
  OrderedLDLT factor(Ac);
  if (!factor.factorize()) throw std::runtime_error("multigrid: the coarsest matrix is not positive definite");
  m_coarse = std::make_unique<NodalSolve>(factor);
  m_coarse_rows = A.rows();
  m_coarse_order.resize(static_cast<std::size_t>(m_coarse_rows));
  for (int i = 0; i < static_cast<int>(m_coarse_rows); ++i)
    m_coarse_order[static_cast<std::size_t>(i)] = factor.ordered(i);
  m_coarse_rhs = Nodal<dim>::Zero(dim, m_coarse_rows);
  m_coarse_bytes = m_coarse->factor_nonzeros() * 2 * (sizeof(double) + sizeof(int));
}

template <int dim> void SymmetricMultigrid<dim>::apply(const Nodal<dim>& b, Nodal<dim>& x) {
  if constexpr (kLanes == dim) {
    cycle(0, b.data(), x.data()); // without levels (a small matrix) that is the exact solve
  } else {
    m_fine_b.template topRows<dim>() = b; // the pad row stays 0
    cycle(0, m_fine_b.data(), m_fine_x.data());
    x = m_fine_x.template topRows<dim>();
  }
}

template <int dim> void SymmetricMultigrid<dim>::cycle(std::size_t l, const double* b, double* x) {
  constexpr int W = kLanes;
  if (l == m_levels.size()) {
    double* c = m_coarse_rhs.data();
    for (Eigen::Index i = 0; i < m_coarse_rows; ++i)
      for (int k = 0; k < dim; ++k) c[m_coarse_order[static_cast<std::size_t>(i)] * dim + k] = b[i * W + k];
    m_coarse->solve_in_place<dim>(m_coarse_rhs);
    for (Eigen::Index i = 0; i < m_coarse_rows; ++i)
      for (int k = 0; k < dim; ++k) x[i * W + k] = c[m_coarse_order[static_cast<std::size_t>(i)] * dim + k];
    return;
  }
  const Level& L = m_levels[l];
  const LevelArrays arrays{L.lower.ptr.data(),
                           L.lower.col.data(),
                           L.upper.ptr.data(),
                           L.upper.col.data(),
                           L.prolong.ptr.data(),
                           L.prolong.col.data(),
                           L.lower.val.data(),
                           L.upper.val.data(),
                           L.prolong.val.data(),
                           L.inv_diag.data(),
                           static_cast<int>(L.inv_diag.size())};
  double *bc = m_b[l].data(), *xc = m_x[l].data();
  presmooth_and_restrict_any<W>(arrays, static_cast<int>(m_b[l].cols()), b, x, bc);
  cycle(l + 1, bc, xc);
  prolongate_and_postsmooth_any<W>(arrays, xc, b, x);
}

template <int dim> std::vector<Eigen::Index> SymmetricMultigrid<dim>::level_sizes() const {
  std::vector<Eigen::Index> sizes;
  for (const Level& L : m_levels) sizes.push_back(static_cast<Eigen::Index>(L.inv_diag.size()));
  sizes.push_back(m_coarse_rows);
  return sizes;
}

template <int dim> std::size_t SymmetricMultigrid<dim>::memory_bytes() const {
  std::size_t bytes = m_coarse_bytes + sizeof(double) * static_cast<std::size_t>(m_coarse_rhs.size());
  auto csr = [](const Csr& c) {
    return c.ptr.size() * sizeof(int) + c.col.size() * sizeof(int) + c.val.size() * sizeof(double);
  };
  for (const Level& L : m_levels)
    bytes += csr(L.lower) + csr(L.upper) + csr(L.prolong) + L.inv_diag.size() * sizeof(double);
  for (std::size_t l = 0; l < m_b.size(); ++l)
    bytes += sizeof(double) * static_cast<std::size_t>(m_b[l].size() + m_x[l].size());
  bytes += sizeof(double) * static_cast<std::size_t>(m_fine_b.size() + m_fine_x.size());
  return bytes;
}

template class SymmetricMultigrid<2>;
template class SymmetricMultigrid<3>;

} // namespace vtb
