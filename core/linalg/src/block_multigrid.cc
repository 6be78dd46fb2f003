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

/// Lanes for a node of nb values: 2, or 4, or 8 (3D coarse nodes: six rigid modes).
constexpr int lanes_of(int nb) {
  return nb <= 2 ? 2 : nb <= 4 ? 4 : 8;
}

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
    Lane<W> s = load<W>(b + i * W);
    for (int k = L.ptr[i]; k < L.diag[i]; ++k) s -= times<W, NB, NB>(L.val + k * F, x + L.col[k] * W);
    store<W>(x + i * W, times<W, NB>(L.dinv + i * B, s));
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

// The 3D sweeps (finest: 3 values on 4 lanes; coarse: 6 rigid modes on 8), built for AVX2 and
// the baseline (vector_clones.hh).
VTB_VECTOR_CLONES void down_fine3(const Arrays& L, const double* b, double* x, double* bc) {
  forward_and_restrict<4, 3, 8, 6>(L, b, x, bc);
}
VTB_VECTOR_CLONES void up_fine3(const Arrays& L, const double* xc, const double* b, double* x) {
  prolongate_and_backward<4, 3, 8, 6>(L, xc, b, x);
}
VTB_VECTOR_CLONES void down_coarse3(const Arrays& L, const double* b, double* x, double* bc) {
  forward_and_restrict<8, 6, 8, 6>(L, b, x, bc);
}
VTB_VECTOR_CLONES void up_coarse3(const Arrays& L, const double* xc, const double* b, double* x) {
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

/// The pattern of a node-level matrix as rows of column indices.
void rows_of(const RowSparse& S, std::vector<int>& ptr, std::vector<int>& col) {
  ptr.assign(1, 0);
  col.clear();
  for (Eigen::Index i = 0; i < S.outerSize(); ++i) {
    for (RowSparse::InnerIterator it(S, i); it; ++it) col.push_back(static_cast<int>(it.col()));
    ptr.push_back(static_cast<int>(col.size()));
  }
}

/// Ones where a dof-level matrix has an entry in a node block (outer / nr, inner / nc), and
/// (diagonal) on every diagonal block: by rows for a row-major A, by columns (the transpose's
/// pattern, the same for a symmetric one) for a column-major one. Built row by row in order,
/// no triplets (a triplet per entry was the multigrid setup's largest transient).
template <class Sparse> RowSparse node_pattern(const Sparse& A, int nr, int nc, bool diagonal = false) {
  RowSparse S(A.outerSize() / nr, A.innerSize() / nc);
  S.reserve(A.nonZeros() / (static_cast<Eigen::Index>(nr) * nc) + S.rows());
  std::vector<int> row;
  for (Eigen::Index I = 0; I < S.rows(); ++I) {
    row.clear();
    if (diagonal) row.push_back(static_cast<int>(I));
    for (Eigen::Index i = I * nr; i < (I + 1) * nr; ++i)
      for (typename Sparse::InnerIterator it(A, i); it; ++it) row.push_back(static_cast<int>(it.index() / nc));
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    S.startVec(I);
    for (int c : row) S.insertBack(I, c) = 1.0;
  }
  S.finalize();
  return S;
}

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

} // namespace

template <int dim> long BlockMultigrid<dim>::offset(int r, int c) const {
  const BlockCsr& A = m_mats.front();
  const int i = r / dim, j = c / dim;
  const auto begin = A.col.begin() + A.ptr[static_cast<std::size_t>(i)];
  const auto end = A.col.begin() + A.ptr[static_cast<std::size_t>(i) + 1];
  const auto it = std::lower_bound(begin, end, j);
  if (it == end || *it != j) return -1;
  return static_cast<long>(it - A.col.begin()) * A.block() + (c % dim) * A.w + r % dim;
}

template <int dim>
BlockMultigrid<dim>::BlockMultigrid(const Eigen::SparseMatrix<double>& A0, const Nodal<dim>& xs,
                                    Eigen::Index coarsest) {
  // A square block matrix with the pattern of a node-level matrix, values zero.
  auto square = [](const RowSparse& pattern, int nb) {
    BlockCsr m;
    m.nb = nb;
    m.w = lanes_of(nb);
    rows_of(pattern, m.ptr, m.col);
    for (int i = 0; i < m.rows(); ++i) {
      const auto b = m.col.begin() + m.ptr[static_cast<std::size_t>(i)], e = m.col.begin() + m.ptr[i + 1];
      const auto it = std::lower_bound(b, e, i);
      if (it == e || *it != i) throw std::runtime_error("multigrid: a node without its diagonal block");
      m.diag.push_back(static_cast<int>(it - m.col.begin()));
    }
    m.vals = std::make_shared<std::vector<double>>(m.col.size() * static_cast<std::size_t>(m.block()), 0.0);
    m.f.assign(m.col.size() * static_cast<std::size_t>(m.packed()) + static_cast<std::size_t>(m.w - m.nb), 0.0f);
    m.trans.resize(m.col.size());
    for (int i = 0; i < m.rows(); ++i)
      for (int k = m.ptr[static_cast<std::size_t>(i)]; k < m.ptr[static_cast<std::size_t>(i) + 1]; ++k) {
        const int j = m.col[static_cast<std::size_t>(k)];
        const auto b = m.col.begin() + m.ptr[static_cast<std::size_t>(j)], e = m.col.begin() + m.ptr[j + 1];
        const auto it = std::lower_bound(b, e, i);
        if (it == e || *it != i) throw std::runtime_error("multigrid: a pattern that is not symmetric");
        m.trans[static_cast<std::size_t>(k)] = static_cast<int>(it - m.col.begin());
      }
    return m;
  };
  // A0 is symmetric: its columns are its rows.
  m_mats.push_back(square(node_pattern(A0, dim, dim, true), dim));
  for (Eigen::Index c = 0; c < A0.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A0, c); it; ++it)
      m_mats.front().val()[static_cast<std::size_t>(offset(static_cast<int>(it.row()), static_cast<int>(c)))] =
          it.value();

  round(m_mats.front());
  // The rigid modes at the finest level, about the nodes' centroid: dim translations, then the
  // rotations (2D: (-y, x); 3D: e_k x r).
  const auto n0 = static_cast<Eigen::Index>(m_mats.front().rows());
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(n0 * dim, kModes);
  const Vec<dim> centre = xs.rowwise().mean();
  for (Eigen::Index i = 0; i < n0; ++i) {
    const Vec<dim> r = xs.col(i) - centre;
    modes.block(i * dim, 0, dim, dim).setIdentity();
    if constexpr (dim == 2) {
      modes(i * 2, 2) = -r.y();
      modes(i * 2 + 1, 2) = r.x();
    } else {
      for (int k = 0; k < 3; ++k) modes.block<3, 1>(i * 3, 3 + k) = Vec<3>::Unit(k).cross(r);
    }
  }

  while (m_mats.back().rows() > coarsest) {
    const std::size_t l = m_mats.size() - 1;
    const int n = m_mats[l].rows(), nb = m_mats[l].nb;
    const RowSparse A = dofs(m_mats[l]);
    // Strength by the blocks' norms (aggregate() compares |a_ij| with sqrt(a_ii a_jj)).
    std::vector<Eigen::Triplet<double>> trip;
    for (int i = 0; i < n; ++i)
      for (int k = m_mats[l].ptr[static_cast<std::size_t>(i)]; k < m_mats[l].ptr[static_cast<std::size_t>(i) + 1];
           ++k) {
        const auto* a = m_mats[l].val().data() + k * m_mats[l].block(); // the pads are 0
        double sq = 0;
        for (int e = 0; e < m_mats[l].block(); ++e) sq += a[e] * a[e];
        trip.emplace_back(i, m_mats[l].col[static_cast<std::size_t>(k)], std::sqrt(sq));
      }
    RowSparse S(n, n);
    S.setFromTriplets(trip.begin(), trip.end());
    std::vector<int> agg;
    // Strong aggregates that coarsen less than kMinCoarsening (nu near 1/2, where the blocks'
    // norms spread: a 6,914-node tissue block at nu 0.49 coarsened 6x, to dense coarse rows)
    // are made again of every coupling (docs/performance.md, item 21).
    const int nc = detail::aggregate_tenfold(S, agg);
    if (nc >= n) break; // nothing to coarsen (no off-diagonal couplings)

    // The tentative prolongator: per aggregate, an orthonormal basis of the rigid modes on its
    // nodes (QR); R of the QR is the coarse node's modes. An aggregate of fewer values than
    // modes (a lone 3D node) leaves the extra coarse values without support: dead.
    std::vector<std::vector<int>> members(static_cast<std::size_t>(nc));
    for (int i = 0; i < n; ++i) members[static_cast<std::size_t>(agg[static_cast<std::size_t>(i)])].push_back(i);
    Eigen::MatrixXd coarse_modes = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nc) * kModes, kModes);
    Level lev;
    auto tr = std::make_shared<Transfer>();
    trip.clear();
    for (int a = 0; a < nc; ++a) {
      const auto& mem = members[static_cast<std::size_t>(a)];
      const auto rows = static_cast<Eigen::Index>(mem.size()) * nb;
      Eigen::MatrixXd B(rows, kModes);
      for (std::size_t t = 0; t < mem.size(); ++t)
        B.middleRows(static_cast<Eigen::Index>(t) * nb, nb) =
            modes.middleRows(static_cast<Eigen::Index>(mem[t]) * nb, nb);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(B);
      const Eigen::Index k = std::min<Eigen::Index>(rows, kModes);
      const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(rows, k);
      coarse_modes.block(static_cast<Eigen::Index>(a) * kModes, 0, k, kModes) =
          qr.matrixQR().topRows(k).template triangularView<Eigen::Upper>();
      for (std::size_t t = 0; t < mem.size(); ++t)
        for (int p = 0; p < nb; ++p)
          for (Eigen::Index c = 0; c < k; ++c)
            trip.emplace_back(mem[t] * nb + p, a * kModes + c, Q(static_cast<Eigen::Index>(t) * nb + p, c));
      for (Eigen::Index c = k; c < kModes; ++c) tr->dead.push_back(a * kModes + static_cast<int>(c));
    }
    RowSparse P0(static_cast<Eigen::Index>(n) * nb, static_cast<Eigen::Index>(nc) * kModes);
    P0.setFromTriplets(trip.begin(), trip.end());

    // Smoothed: P = (I - w D^-1 A) P0 with D the diagonal blocks, w = 4/3 over the spectral
    // radius of D^-1 A (twenty power iterations, 5 % margin, as the scalar cycle's).
    trip.clear();
    for (int i = 0; i < n; ++i) {
      const double* a = m_mats[l].val().data() + m_mats[l].diag[static_cast<std::size_t>(i)] * m_mats[l].block();
      Small D(nb, nb);
      for (int p = 0; p < nb; ++p)
        for (int q = 0; q < nb; ++q) D(p, q) = a[q * m_mats[l].w + p];
      const Small Dinv = D.inverse();
      for (int p = 0; p < nb; ++p)
        for (int q = 0; q < nb; ++q) trip.emplace_back(i * nb + p, i * nb + q, Dinv(p, q));
    }
    RowSparse Dinv(A.rows(), A.cols());
    Dinv.setFromTriplets(trip.begin(), trip.end());
    const RowSparse DA = Dinv * A;
    Eigen::VectorXd v = Eigen::VectorXd::Ones(A.rows()), y(A.rows());
    for (Eigen::Index i = 0; i < v.size(); i += 2) v[i] = -1.0;
    double rho = 0;
    for (int it = 0; it < 20; ++it) {
      y = DA * v;
      rho = y.norm() / v.norm();
      v = y / y.norm();
    }
    // (Unsmoothed, w = 0, the cycle contracted by 0.92 on the tests' box; w = 2/3 over rho: 0.84;
    // 4/3: 0.74, at 1.8x the unsmoothed cycle's cost on the 10k slab: denser P and coarse rows.)
    const double w = (4.0 / 3.0) / (1.05 * rho);
    RowSparse P = P0 - w * RowSparse(DA * P0);
    P.prune(0.0);

    // Node-level patterns of P, A P and P^T A P (ones: the products cannot cancel).
    const RowSparse Pn = node_pattern(P, nb, kModes);
    const RowSparse An = node_pattern(A, nb, nb);
    const RowSparse APn = An * Pn;
    const RowSparse Cn = RowSparse(Pn.transpose()) * APn;
    const int wf = m_mats[l].w;
    rows_of(Pn, tr->pptr, tr->pcol);
    const int wc = lanes_of(kModes);
    tr->pval.assign(tr->pcol.size() * static_cast<std::size_t>(wf * kModes), 0.0f);
    tr->ptrans.assign(tr->pcol.size() * static_cast<std::size_t>(wc * nb), 0.0f);
    for (int i = 0; i < n; ++i)
      for (int kk = tr->pptr[static_cast<std::size_t>(i)]; kk < tr->pptr[static_cast<std::size_t>(i) + 1]; ++kk) {
        const int I = tr->pcol[static_cast<std::size_t>(kk)];
        for (int p = 0; p < nb; ++p)
          for (int c = 0; c < kModes; ++c) {
            const auto value = static_cast<float>(P.coeff(i * nb + p, I * kModes + c)); // P from here on
            tr->pval[static_cast<std::size_t>(kk * wf * kModes + c * wf + p)] = value;
            tr->ptrans[static_cast<std::size_t>(kk * wc * nb + p * wc + c)] = value;
          }
      }
    rows_of(APn, tr->apptr, tr->apcol);
    int widest = 0;
    for (int i = 0; i < n; ++i)
      widest = std::max(widest, tr->apptr[static_cast<std::size_t>(i) + 1] - tr->apptr[static_cast<std::size_t>(i)]);
    lev.ap_row.assign(static_cast<std::size_t>(widest) * static_cast<std::size_t>(wf * kModes), 0.0);
    lev.t = std::move(tr);
    lev.marker.assign(static_cast<std::size_t>(nc), -1);
    lev.inv_diag.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(m_mats[l].block()), 0.0);
    m_levels.push_back(std::move(lev));
    m_mats.push_back(square(Cn, kModes));
    for (int stage = 1 + 3 * static_cast<int>(l); stage <= 3 + 3 * static_cast<int>(l); ++stage) { // its values
      bool done = false;
      m_work += refresh_stage(stage, 0, std::numeric_limits<int>::max(), done) + 1;
    }
    m_b.emplace_back(static_cast<std::size_t>(nc) * static_cast<std::size_t>(m_mats.back().w), 0.0);
    m_x.emplace_back(m_b.back().size(), 0.0);
    modes = coarse_modes;
  }

  make_coarse_factor();
  // The setup's loop made every level's values; the rest of a refresh, its work counted.
  bool done = false;
  m_work += refresh_stage(1 + 3 * static_cast<int>(m_levels.size()), 0, 0, done) + 1;
  m_work += 15.0 * static_cast<double>(m_mats.front().col.size()) * m_mats.front().nb * m_mats.front().nb +
            1; // the finest matrix's rounding (refresh_stage's unit)
}

template <int dim>
BlockMultigrid<dim>::BlockMultigrid(const BlockMultigrid& other)
    : m_mats(other.m_mats), m_levels(other.m_levels), m_b(other.m_b), m_x(other.m_x), m_work(other.m_work) {
  make_coarse_factor();
  finish(); // the copied values' diagonal inverses (the same) and coarsest factor
}

template <int dim> RowSparse BlockMultigrid<dim>::dofs(const BlockCsr& m) {
  // Row by row in order, no triplets.
  RowSparse S(m.rows() * m.nb, m.rows() * m.nb);
  S.reserve(static_cast<Eigen::Index>(m.col.size()) * m.nb * m.nb);
  for (int i = 0; i < m.rows(); ++i)
    for (int p = 0; p < m.nb; ++p) {
      S.startVec(i * m.nb + p);
      for (int k = m.ptr[static_cast<std::size_t>(i)]; k < m.ptr[static_cast<std::size_t>(i) + 1]; ++k)
        for (int q = 0; q < m.nb; ++q)
          S.insertBack(i * m.nb + p, m.col[static_cast<std::size_t>(k)] * m.nb + q) =
              m.val()[static_cast<std::size_t>(k * m.block() + q * m.w + p)];
    }
  S.finalize();
  return S;
}

template <int dim> void BlockMultigrid<dim>::make_coarse_factor() {
  // The coarsest matrix for a sparse LDL^T (its pattern: every value of every block; the values
  // come with finish()).
  const BlockCsr& C = m_mats.back();
  m_coarse = std::make_unique<OrderedLDLT>(Eigen::SparseMatrix<double>(dofs(C)), C.nb);
  m_coarse_offset.assign(C.f.size(), -1);
  for (int i = 0; i < C.rows(); ++i)
    for (int k = C.ptr[static_cast<std::size_t>(i)]; k < C.ptr[static_cast<std::size_t>(i) + 1]; ++k)
      for (int p = 0; p < C.nb; ++p)
        for (int q = 0; q < C.nb; ++q) {
          const int r = m_coarse->ordered(i * C.nb + p);
          const int c = m_coarse->ordered(C.col[static_cast<std::size_t>(k)] * C.nb + q);
          if (r <= c) m_coarse_offset[static_cast<std::size_t>(k * C.packed() + q * C.nb + p)] = m_coarse->offset(r, c);
        }
  m_coarse_order.resize(static_cast<std::size_t>(C.rows()) * static_cast<std::size_t>(C.nb));
  for (std::size_t d = 0; d < m_coarse_order.size(); ++d) m_coarse_order[d] = m_coarse->ordered(static_cast<int>(d));
  m_coarse_rhs = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m_coarse_order.size()), 1);
}

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
