#include "vtb/linalg/block_multigrid.hh"

#include "aggregation.hh"
#include "vtb/linalg/lanes.hh"
#include "vtb/linalg/vector_clones.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vtb {

namespace {

using namespace detail; // Lane, load, store (lanes.hh); RowSparse, aggregate, smoothed_prolongator

/// One level's raw arrays, for the sweeps below.
struct Arrays {
  const int *ptr, *col, *diag, *pp, *pc;
  const float* val;
  const double* dinv;
  const float *pv, *ptv; ///< ptv: P's blocks transposed
  int n, nc;
};

/// The NB x NB block at a (NB columns of W lanes) times the node x (its first NB values).
/// The NB x NB block at a (NB columns of W lanes, double or float) times the node x (its first
/// NB values), in two partial sums (even and odd columns), so that the adds form two shorter
/// chains.
/// S: the columns' stride (W for padded blocks; NB for the packed single-precision matrices,
/// whose lanes past NB then hold the next values, unused).
template <int W, int NB, int S = W, class T, class X>
[[gnu::always_inline]] inline Lane<W> times(const T* a, const X* x) {
  Lane<W> even = load<W>(a) * static_cast<double>(x[0]), odd = load<W>(a + S) * static_cast<double>(x[1]);
  for (int q = 2; q < NB; q += 2) {
    even += load<W>(a + q * S) * static_cast<double>(x[q]);
    if (q + 1 < NB) odd += load<W>(a + (q + 1) * S) * static_cast<double>(x[q + 1]);
  }
  return even + odd;
}
template <int W, int NB, int S = W, class T> [[gnu::always_inline]] inline Lane<W> times(const T* a, Lane<W> x) {
  double v[W];
  store<W>(v, x);
  return times<W, NB, S>(a, static_cast<const double*>(v));
}

/// Forward block Gauss-Seidel from x = 0 (only the lower blocks meet nonzero x), then the
/// restricted residual bc = P^T (b - A x) = P^T (-U x), as the scalar cycle does (the diagonal
/// and lower parts cancel b exactly after the sweep); bc is zeroed here. P's blocks are NBC
/// columns of W lanes (transposed: NB columns of WC lanes), a coarse node WC lanes.
template <int W, int NB, int WC, int NBC>
[[gnu::always_inline]] inline void forward_and_restrict(const Arrays& L, const double* b, double* x, double* bc) {
  constexpr int B = W * NB, F = NB * NB, PTB = WC * NB; // F: a packed block (Arrays::val)
  for (int i = 0; i < L.n; ++i) {
    Lane<W> s = load<W>(b + i * W), t = {}; // two sums: two shorter chains of dependent adds
    int k = L.ptr[i];
    for (; k + 1 < L.diag[i]; k += 2) {
      s -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
      t -= times<W, NB, NB>(L.val + (k + 1) * F, x + L.col[k + 1] * W);
    }
    if (k < L.diag[i]) s -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
    store<W>(x + i * W, times<W, NB>(L.dinv + i * B, s + t));
  }
  for (int c = 0; c < L.nc * WC; ++c) bc[c] = 0;
  for (int i = 0; i < L.n; ++i) {
    Lane<W> r = {};
    for (int k = L.diag[i] + 1; k < L.ptr[i + 1]; ++k) r -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
    double rv[W];
    store<W>(rv, r);
    for (int p = L.pp[i]; p < L.pp[i + 1]; ++p) {
      double* t = bc + L.pc[p] * WC;
      store<WC>(t, load<WC>(t) + times<WC, NB>(L.ptv + p * PTB, rv));
    }
  }
}

/// Rows ahead that the backward sweep prefetches.
constexpr int kAhead = 4;

/// x += P xc, then backward block Gauss-Seidel with the whole matrix.
template <int W, int NB, int WC, int NBC>
[[gnu::always_inline]] inline void prolongate_and_backward(const Arrays& L, const double* xc, const double* b,
                                                           double* x) {
  constexpr int B = W * NB, F = NB * NB, PB = W * NBC;
  for (int i = 0; i < L.n; ++i) {
    Lane<W> s = load<W>(x + i * W);
    for (int p = L.pp[i]; p < L.pp[i + 1]; ++p) s += times<W, NBC>(L.pv + p * PB, xc + L.pc[p] * WC);
    store<W>(x + i * W, s);
  }
  for (int i = L.n - 1; i >= 0; --i) {
    // The rows are read backward, each forward: a stream the hardware's prefetchers do not
    // follow. Row i - kAhead's blocks are asked for now (one touch per cache line).
    if (i >= kAhead) {
      const char* first = reinterpret_cast<const char*>(L.val + L.ptr[i - kAhead] * F);
      const char* last = reinterpret_cast<const char*>(L.val + L.ptr[i - kAhead + 1] * F);
      for (const char* c = first; c < last; c += 64) __builtin_prefetch(c);
    }
    Lane<W> s = load<W>(b + i * W), t = {}; // two sums: two shorter chains of dependent adds
    for (int k = L.ptr[i]; k < L.diag[i]; ++k) s -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
    for (int k = L.diag[i] + 1; k < L.ptr[i + 1]; ++k) t -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
    store<W>(x + i * W, times<W, NB>(L.dinv + i * B, s + t));
  }
}

// The 3D sweeps (finest: 3 values on 4 lanes; coarse: 6 rigid modes on 8), built for AVX-512F, AVX2
// and the baseline (vector_clones.hh).
VTB_VECTOR_CLONES_WIDE void down_fine3(const Arrays& L, const double* b, double* x, double* bc) {
  forward_and_restrict<4, 3, 8, 6>(L, b, x, bc);
}
VTB_VECTOR_CLONES_WIDE void up_fine3(const Arrays& L, const double* xc, const double* b, double* x) {
  prolongate_and_backward<4, 3, 8, 6>(L, xc, b, x);
}
VTB_VECTOR_CLONES_WIDE void down_coarse3(const Arrays& L, const double* b, double* x, double* bc) {
  forward_and_restrict<8, 6, 8, 6>(L, b, x, bc);
}
VTB_VECTOR_CLONES_WIDE void up_coarse3(const Arrays& L, const double* xc, const double* b, double* x) {
  prolongate_and_backward<8, 6, 8, 6>(L, xc, b, x);
}

template <int dim> void sweep_down(const Arrays& L, int nb, const double* b, double* x, double* bc) {
  if constexpr (dim == 3)
    nb == 3 ? down_fine3(L, b, x, bc) : down_coarse3(L, b, x, bc);
  else
    nb == 2 ? forward_and_restrict<2, 2, 4, 3>(L, b, x, bc) : forward_and_restrict<4, 3, 4, 3>(L, b, x, bc);
}
template <int dim> void sweep_up(const Arrays& L, int nb, const double* xc, const double* b, double* x) {
  if constexpr (dim == 3)
    nb == 3 ? up_fine3(L, xc, b, x) : up_coarse3(L, xc, b, x);
  else
    nb == 2 ? prolongate_and_backward<2, 2, 4, 3>(L, xc, b, x) : prolongate_and_backward<4, 3, 4, 3>(L, xc, b, x);
}

} // namespace

template <int dim> void BlockMultigrid<dim>::finish_coarse(std::size_t l) {
  // 1 on the dead values' diagonal (their P columns are zero); then what the cycle reads.
  BlockCsr& C = m_mats[l + 1];
  for (int d : m_levels[l].t->dead)
    C.val()[static_cast<std::size_t>(C.diag[static_cast<std::size_t>(d / C.nb)] * C.block() +
                                     (d % C.nb) * (C.w + 1))] += 1.0;
  round(C);
}

template <int dim> double BlockMultigrid<dim>::refresh_stage(int stage, int begin, int end, bool& done) {
  // The work in multiply-adds of the lanes computed, and for the other loops their measured
  // cost in the same unit (on a 2,415-node 3D hierarchy: a rounded value about 15, a
  // multiply-add of the coarsest factor about 6, a diagonal block's inverse about nb^3 x 10).
  constexpr double kRoundValue = 15, kFactorAdd = 6, kInverse = 10;
  const int levels = static_cast<int>(m_levels.size());
  done = true;
  if (stage == 0) {
    const BlockCsr& A = m_mats.front();
    round(m_mats.front());
    return kRoundValue * static_cast<double>(A.col.size()) * A.nb * A.nb;
  }
  if (stage == 1 + 3 * levels) {
    finish();
    double inverses = 0;
    for (const BlockCsr& m : m_mats) inverses += static_cast<double>(m.rows()) * m.nb * m.nb * m.nb;
    return kInverse * inverses + kFactorAdd * m_coarse->factorize_work();
  }
  const auto l = static_cast<std::size_t>((stage - 1) / 3);
  const int kind = (stage - 1) % 3;
  if (kind == 2) {
    finish_coarse(l);
    const BlockCsr& C = m_mats[l + 1];
    return kRoundValue * static_cast<double>(C.col.size()) * C.nb * C.nb;
  }
  const int rows = kind == 0 ? m_mats[l + 1].rows() : m_mats[l].rows();
  end = std::min(end, rows);
  done = end == rows;
  if (kind == 0) { // the coarse rows' values zeroed, for the products to add into
    BlockCsr& C = m_mats[l + 1];
    const auto first = static_cast<std::size_t>(C.ptr[static_cast<std::size_t>(begin)] * C.block());
    const auto last = static_cast<std::size_t>(C.ptr[static_cast<std::size_t>(end)] * C.block());
    std::fill(C.val().begin() + static_cast<long>(first), C.val().begin() + static_cast<long>(last), 0.0);
    return static_cast<double>(last - first) / 4; // a quarter of a multiply-add per value
  }
  const bool fine3 = m_mats[l].nb == 3;
  if constexpr (dim == 3)
    return fine3 ? galerkin_rows<4, 3, 8>(l, begin, end) : galerkin_rows<8, 6, 8>(l, begin, end);
  else
    return m_mats[l].nb == 2 ? galerkin_rows<2, 2, 4>(l, begin, end) : galerkin_rows<4, 3, 4>(l, begin, end);
}

template <int dim> void BlockMultigrid<dim>::begin_refresh() {
  m_stage = 0;
  m_row = 0;
}

template <int dim> bool BlockMultigrid<dim>::refresh_part(double share) {
  // Stages in order, rows of the Galerkin products a chunk at a time, until the share of a
  // whole refresh's work is done (a whole refresh when the work is not yet counted).
  constexpr int kChunk = 16;
  const int last = 1 + 3 * static_cast<int>(m_levels.size());
  const double budget = m_work > 0 ? share * m_work : std::numeric_limits<double>::infinity();
  double done = 0;
  while (m_stage <= last && (done < budget || done == 0)) {
    bool complete = false;
    done += refresh_stage(m_stage, m_row, m_row + kChunk, complete) + 1;
    m_row += kChunk;
    if (complete) {
      ++m_stage;
      m_row = 0;
    }
  }
  return m_stage > last;
}

template <int dim> void BlockMultigrid<dim>::round(BlockCsr& m) {
  // Each value once, from the block on or above the diagonal (the computed coarse matrices are
  // symmetric only to round-off), mirrored below it; then each dof row's rounding errors added
  // to its diagonal value, rounded up: the stored matrix minus val is symmetric and
  // diagonally dominant with a nonnegative diagonal, so positive semidefinite. The cycle is
  // then one for a matrix >= val, and B <= that matrix's inverse <= val's (docs/method.md).
  const int B = m.block(), F = m.packed(); // val's blocks padded, f's packed
  for (int i = 0; i < m.rows(); ++i)
    for (int k = m.ptr[static_cast<std::size_t>(i)]; k < m.ptr[static_cast<std::size_t>(i) + 1]; ++k) {
      const int j = m.col[static_cast<std::size_t>(k)];
      if (j < i) continue;
      const int t = m.trans[static_cast<std::size_t>(k)];
      for (int p = 0; p < m.nb; ++p)
        for (int q = 0; q < m.nb; ++q) {
          if (j == i && q < p) continue;
          const float v = static_cast<float>(m.val()[static_cast<std::size_t>(k * B + q * m.w + p)]);
          m.f[static_cast<std::size_t>(k * F + q * m.nb + p)] = v;
          m.f[static_cast<std::size_t>(t * F + p * m.nb + q)] = v;
        }
    }
  for (int i = 0; i < m.rows(); ++i)
    for (int p = 0; p < m.nb; ++p) {
      double shift = 0;
      for (int k = m.ptr[static_cast<std::size_t>(i)]; k < m.ptr[static_cast<std::size_t>(i) + 1]; ++k)
        for (int q = 0; q < m.nb; ++q) {
          const auto e = static_cast<std::size_t>(k * B + q * m.w + p);
          const int j = m.col[static_cast<std::size_t>(k)];
          // the error against the value the row's symmetric counterpart was rounded from
          const double exact =
              (j > i || (j == i && q >= p))
                  ? m.val()[e]
                  : m.val()[static_cast<std::size_t>(m.trans[static_cast<std::size_t>(k)] * B + p * m.w + q)];
          shift += std::abs(static_cast<double>(m.f[static_cast<std::size_t>(k * F + q * m.nb + p)]) - exact);
        }
      const auto d = static_cast<std::size_t>(m.diag[static_cast<std::size_t>(i)] * F + p * m.nb + p);
      const double target = static_cast<double>(m.f[d]) + shift;
      float v = static_cast<float>(target);
      if (static_cast<double>(v) < target) v = std::nextafter(v, std::numeric_limits<float>::infinity());
      m.f[d] = v;
    }
}

template <int dim>
template <int W, int NB, int WC>
double BlockMultigrid<dim>::galerkin_rows(std::size_t l, int begin, int end) {
  constexpr int NBC = kModes, AF = NB * NB, PB = W * NBC, PTB = WC * NB, CB = WC * NBC; // AF: A's packed block
  const BlockCsr& A = m_mats[l];
  BlockCsr& C = m_mats[l + 1];
  Level& lev = m_levels[l];
  const Transfer& t = *lev.t;
  int* marker = lev.marker.data();
  double* row = lev.ap_row.data();
  const int *ptr = A.ptr.data(), *col = A.col.data(), *pp = t.pptr.data(), *pc = t.pcol.data();
  const int *apptr = t.apptr.data(), *apcol = t.apcol.data(), *cptr = C.ptr.data(), *ccol = C.col.data();
  const float *av = A.f.data(), *pv = t.pval.data(), *ptv = t.ptrans.data();
  double* cv = C.val().data();
  long products = 0, coarse_products = 0;
  for (int i = begin; i < end; ++i) {
    // Row i of A P, through the marker of its coarse columns: column c of block (i, J) +=
    // A_ij times column c of P_jJ.
    const int a0 = apptr[i], a1 = apptr[i + 1];
    for (int q = a0; q < a1; ++q) {
      marker[apcol[q]] = q - a0;
      std::fill_n(row + (q - a0) * PB, PB, 0.0);
    }
    for (int k = ptr[i]; k < ptr[i + 1]; ++k) {
      const float* a = av + k * AF;
      products += pp[col[k] + 1] - pp[col[k]];
      for (int p = pp[col[k]]; p < pp[col[k] + 1]; ++p) {
        const float* pj = pv + p * PB;
        double* r = row + marker[pc[p]] * PB;
        for (int c = 0; c < NBC; ++c) store<W>(r + c * W, load<W>(r + c * W) + times<W, NB, NB>(a, pj + c * W));
      }
    }
    // Its share of P^T A P: column c of block (I, J) += P_iI^T times column c of (A P)_iJ, for
    // each block P_iI; row I's columns found by a walk (both rows sorted, A P's within C's).
    // Each (I, J) gathers its terms in the order of i, as a product by coarse rows would.
    for (int kk = pp[i]; kk < pp[i + 1]; ++kk) {
      const int I = pc[kk];
      const float* pt = ptv + kk * PTB;
      coarse_products += a1 - a0;
      int at = cptr[I];
      for (int q = a0; q < a1; ++q) {
        while (ccol[at] < apcol[q]) ++at;
        const double* a = row + (q - a0) * PB;
        double* target = cv + at * CB;
        for (int c = 0; c < NBC; ++c)
          store<WC>(target + c * WC, load<WC>(target + c * WC) + times<WC, NB>(pt, a + c * W));
      }
    }
  }
  // each product: NBC columns of W (or WC) lanes, NB terms
  return static_cast<double>(products) * W * NB * NBC + static_cast<double>(coarse_products) * WC * NB * NBC;
}

template <int dim> void BlockMultigrid<dim>::refresh() {
  // Every stage whole, in refresh_part's order; the work counted for its shares.
  double work = 0;
  bool done = false;
  for (int stage = 0; stage <= 1 + 3 * static_cast<int>(m_levels.size()); ++stage)
    work += refresh_stage(stage, 0, std::numeric_limits<int>::max(), done) + 1;
  m_work = work;
}

template <int dim> void BlockMultigrid<dim>::finish() {
  for (std::size_t l = 0; l < m_levels.size(); ++l) {
    const BlockCsr& A = m_mats[l];
    double* inv = m_levels[l].inv_diag.data();
    Small D(A.nb, A.nb);
    for (int i = 0; i < A.rows(); ++i) {
      const float* a = A.f.data() + A.diag[static_cast<std::size_t>(i)] * A.packed();
      for (int p = 0; p < A.nb; ++p)
        for (int q = 0; q < A.nb; ++q) D(p, q) = a[q * A.nb + p];
      const Small Dinv = D.inverse();
      if (!Dinv.allFinite()) throw std::runtime_error("multigrid: a singular diagonal block");
      for (int p = 0; p < A.nb; ++p)
        for (int q = 0; q < A.nb; ++q) inv[i * A.block() + q * A.w + p] = Dinv(p, q);
    }
  }
  double* v = m_coarse->values();
  std::fill_n(v, m_coarse->nonzeros(), 0.0);
  const std::vector<float>& cv = m_mats.back().f;
  for (std::size_t e = 0; e < m_coarse_offset.size(); ++e) // (f's tail, past the blocks, has none)
    if (m_coarse_offset[e] >= 0) v[m_coarse_offset[e]] = cv[e];
  if (!m_coarse->factorize()) throw std::runtime_error("multigrid: the coarsest matrix is not positive definite");
}

template <int dim> void BlockMultigrid<dim>::apply(const double* b, double* x) {
  cycle(0, b, x);
}

template <int dim> void BlockMultigrid<dim>::cycle(std::size_t l, const double* b, double* x) {
  const BlockCsr& A = m_mats[l];
  if (l == m_levels.size()) {
    double* c = m_coarse_rhs.data();
    for (int i = 0; i < A.rows(); ++i)
      for (int p = 0; p < A.nb; ++p) c[m_coarse_order[static_cast<std::size_t>(i * A.nb + p)]] = b[i * A.w + p];
    m_coarse->solve_in_place(m_coarse_rhs);
    for (int i = 0; i < A.rows(); ++i)
      for (int p = 0; p < A.nb; ++p) x[i * A.w + p] = c[m_coarse_order[static_cast<std::size_t>(i * A.nb + p)]];
    return;
  }
  const Level& L = m_levels[l];
  const Transfer& T = *L.t;
  const Arrays arrays{A.ptr.data(),      A.col.data(),  A.diag.data(),   T.pptr.data(), T.pcol.data(),       A.f.data(),
                      L.inv_diag.data(), T.pval.data(), T.ptrans.data(), A.rows(),      m_mats[l + 1].rows()};
  double *bc = m_b[l].data(), *xc = m_x[l].data();
  sweep_down<dim>(arrays, A.nb, b, x, bc);
  cycle(l + 1, bc, xc);
  sweep_up<dim>(arrays, A.nb, xc, b, x);
}

template <int dim> std::vector<Eigen::Index> BlockMultigrid<dim>::level_sizes() const {
  std::vector<Eigen::Index> sizes;
  for (const BlockCsr& A : m_mats) sizes.push_back(A.rows());
  return sizes;
}

template <int dim> std::size_t BlockMultigrid<dim>::memory_bytes() const {
  auto ints = [](const std::vector<int>& v) { return v.size() * sizeof(int); };
  auto doubles = [](const std::vector<double>& v) { return v.size() * sizeof(double); };
  std::size_t bytes = static_cast<std::size_t>(m_coarse->nonzeros()) * (sizeof(double) + sizeof(int)) * 2 +
                      ints(m_coarse_offset) + ints(m_coarse_order) +
                      sizeof(double) * static_cast<std::size_t>(m_coarse_rhs.size());
  auto floats = [](const std::vector<float>& v) { return v.size() * sizeof(float); };
  for (const BlockCsr& A : m_mats)
    bytes += ints(A.ptr) + ints(A.col) + ints(A.diag) + ints(A.trans) + doubles(A.val()) + floats(A.f);
  for (const Level& L : m_levels) {
    bytes += doubles(L.inv_diag) + doubles(L.ap_row) + ints(L.marker);
    // the shared transfers counted in full by each copy: the bytes the cycle needs
    bytes += ints(L.t->pptr) + ints(L.t->pcol) + floats(L.t->pval) + floats(L.t->ptrans) + ints(L.t->apptr) +
             ints(L.t->apcol) + ints(L.t->dead);
  }
  for (std::size_t l = 0; l < m_b.size(); ++l) bytes += doubles(m_b[l]) + doubles(m_x[l]);
  return bytes;
}

template class BlockMultigrid<2>;
template class BlockMultigrid<3>;

} // namespace vtb
