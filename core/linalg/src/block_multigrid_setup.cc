#include "vtb/linalg/block_multigrid.hh"

#include "aggregation.hh"
#include "vtb/linalg/lanes.hh"
#include "vtb/linalg/vector_clones.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

// The multigrid's set-up: the levels by smoothed aggregation and their transfer patterns, and
// the coarsest factor's pattern. Refreshing the values and the V-cycle: block_multigrid.cc.
namespace vtb {
namespace {

using namespace detail; // RowSparse, aggregate, smoothed_prolongator (aggregation.hh)

/// Lanes for a node of nb values: 2, or 4, or 8 (3D coarse nodes: six rigid modes).
constexpr int lanes_of(int nb) {
  return nb <= 2 ? 2 : nb <= 4 ? 4 : 8;
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
/// no triplets (a triplet per entry would be the multigrid setup's largest transient).
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

// One function of about 180 lines, kept whole: each level is built from the one before (its
// aggregates, rigid modes, prolongator and the patterns of P, A P and P^T A P), and its parts
// share a dozen of that level's arrays; split, they would pass them all by argument.
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

template BlockMultigrid<2>::BlockMultigrid(const Eigen::SparseMatrix<double>&, const Nodal<2>&, Eigen::Index);
template BlockMultigrid<3>::BlockMultigrid(const Eigen::SparseMatrix<double>&, const Nodal<3>&, Eigen::Index);
template BlockMultigrid<2>::BlockMultigrid(const BlockMultigrid&);
template BlockMultigrid<3>::BlockMultigrid(const BlockMultigrid&);
template long BlockMultigrid<2>::offset(int, int) const;
template long BlockMultigrid<3>::offset(int, int) const;
template Eigen::SparseMatrix<double, Eigen::RowMajor> BlockMultigrid<2>::dofs(const BlockCsr&);
template Eigen::SparseMatrix<double, Eigen::RowMajor> BlockMultigrid<3>::dofs(const BlockCsr&);
template void BlockMultigrid<2>::make_coarse_factor();
template void BlockMultigrid<3>::make_coarse_factor();

} // namespace vtb
