#include "vtb/core/multigrid.hh"
#include "vtb/core/ordered_ldlt.hh"

#include <cmath>
#include <stdexcept>

namespace vtb {

namespace {

using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Aggregate of each row of A (graph of the off-diagonal entries); returns their count.
int aggregate(const RowSparse& A0, std::vector<int>& agg) {
  // Strong couplings only: |a_ij| >= theta sqrt(a_ii a_jj). A node of a 3D tetrahedral mesh
  // has about 14 neighbours, so a Laplacian's couplings are near 1/14 = 0.07 of the diagonal;
  // theta = 0.04 drops the weakest (measured: the V-cycle's contraction on the 9,864-node
  // slab is 0.46 with all couplings, 0.42 at 0.04, at 15 % more cost per cycle than 0.02 ..).
  constexpr double theta = 0.04;
  RowSparse A = A0;
  const Eigen::VectorXd d = A0.diagonal();
  A.prune([&](Eigen::Index i, Eigen::Index j, double v) {
    return i == j || std::abs(v) >= theta * std::sqrt(d[i] * d[j]);
  });
  const auto n = static_cast<int>(A.rows());
  agg.assign(static_cast<std::size_t>(n), -1);
  int count = 0;
  // Seeds: a node whose neighbours are all unassigned takes them all.
  for (int i = 0; i < n; ++i) {
    if (agg[static_cast<std::size_t>(i)] >= 0) continue;
    bool free = true;
    for (RowSparse::InnerIterator it(A, i); it && free; ++it)
      if (it.col() != i && agg[static_cast<std::size_t>(it.col())] >= 0) free = false;
    if (!free) continue;
    agg[static_cast<std::size_t>(i)] = count;
    for (RowSparse::InnerIterator it(A, i); it; ++it) agg[static_cast<std::size_t>(it.col())] = count;
    ++count;
  }
  // The rest: join the neighbouring aggregate of the strongest coupling |a_ij|. Every such
  // node has an assigned neighbour (else it would have seeded); an isolated one stands alone.
  std::vector<int> joined(agg);
  for (int i = 0; i < n; ++i) {
    if (agg[static_cast<std::size_t>(i)] >= 0) continue;
    double best = -1;
    for (RowSparse::InnerIterator it(A, i); it; ++it)
      if (it.col() != i && agg[static_cast<std::size_t>(it.col())] >= 0 && std::abs(it.value()) > best) {
        best = std::abs(it.value());
        joined[static_cast<std::size_t>(i)] = agg[static_cast<std::size_t>(it.col())];
      }
    if (joined[static_cast<std::size_t>(i)] < 0) joined[static_cast<std::size_t>(i)] = count++;
  }
  agg.swap(joined);
  return count;
}

/// P = (I - w D^-1 A) P0, P0 the aggregates' indicator, w = 4/3 / rho with rho the spectral
/// radius of D^-1 A: a power-iteration estimate with a 5 % margin, never above Gershgorin's
/// bound max_i sum_j |a_ij| / a_ii.
RowSparse smoothed_prolongator(const RowSparse& A, const std::vector<int>& agg, int nc) {
  const auto n = A.rows();
  Eigen::VectorXd diag(n);
  double rho = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0;
    diag[i] = 0;
    for (RowSparse::InnerIterator it(A, i); it; ++it) {
      sum += std::abs(it.value());
      if (it.col() == i) diag[i] = it.value();
    }
    if (!(diag[i] > 0)) throw std::runtime_error("multigrid: a matrix row without a positive diagonal");
    rho = std::max(rho, sum / diag[i]);
  }
  // Gershgorin's bound is 2 for a Laplacian plus mass; the spectral radius of D^-1 A is
  // nearer 1.5 on a tetrahedral mesh, and w = 4/3 over the bound under-smooths P (the
  // V-cycle's contraction 0.72 against 0.64 on the 9,864-node slab). Twenty power iterations,
  // 5 % above their estimate, and never above the bound.
  const Eigen::VectorXd inv_diag = diag.cwiseInverse();
  Eigen::VectorXd v = Eigen::VectorXd::Ones(n), y(n);
  for (Eigen::Index i = 0; i < n; i += 2) v[i] = -1.0; // oscillating: the high end of the spectrum
  double estimate = 0;
  for (int k = 0; k < 20; ++k) {
    y = inv_diag.asDiagonal() * (A * v);
    estimate = y.norm() / v.norm();
    v = y / y.norm();
  }
  rho = std::min(rho, 1.05 * estimate);
  const double w = (4.0 / 3.0) / rho;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (Eigen::Index i = 0; i < n; ++i) {
    trip.emplace_back(i, agg[static_cast<std::size_t>(i)], 1.0);
    for (RowSparse::InnerIterator it(A, i); it; ++it)
      trip.emplace_back(i, agg[static_cast<std::size_t>(it.col())], -w * it.value() / diag[i]);
  }
  RowSparse P(n, nc);
  P.setFromTriplets(trip.begin(), trip.end()); // sums duplicates
  P.prune(0.0);
  return P;
}

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

template <int dim> using Cv = Eigen::Map<const Vec<dim>>;
template <int dim> using Mv = Eigen::Map<Vec<dim>>;

} // namespace

template <int dim>
SymmetricMultigrid<dim>::SymmetricMultigrid(const Eigen::SparseMatrix<double>& A0, Eigen::Index coarsest) {
  RowSparse A(A0);
  std::vector<int> agg;
  while (A.rows() > coarsest) {
    const int nc = aggregate(A, agg);
    if (nc >= A.rows()) break; // nothing to coarsen (no off-diagonal couplings)
    const RowSparse P = smoothed_prolongator(A, agg, nc);
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
    m_b.emplace_back(Nodal<dim>::Zero(dim, A.rows()));
    m_x.emplace_back(Nodal<dim>::Zero(dim, A.rows()));
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
  cycle(0, b.data(), x.data()); // without levels (a small matrix) that is the exact solve
}

template <int dim> void SymmetricMultigrid<dim>::cycle(std::size_t l, const double* b, double* x) {
  if (l == m_levels.size()) {
    double* c = m_coarse_rhs.data();
    for (Eigen::Index i = 0; i < m_coarse_rows; ++i)
      Mv<dim>(c + m_coarse_order[static_cast<std::size_t>(i)] * dim) = Cv<dim>(b + i * dim);
    m_coarse->solve_in_place<dim>(m_coarse_rhs);
    for (Eigen::Index i = 0; i < m_coarse_rows; ++i)
      Mv<dim>(x + i * dim) = Cv<dim>(c + m_coarse_order[static_cast<std::size_t>(i)] * dim);
    return;
  }
  const Level& L = m_levels[l];
  const auto n = static_cast<int>(L.inv_diag.size());
  const int *lp = L.lower.ptr.data(), *lc = L.lower.col.data(), *up = L.upper.ptr.data(), *uc = L.upper.col.data();
  const double *lv = L.lower.val.data(), *uv = L.upper.val.data(), *dinv = L.inv_diag.data();
  // Forward Gauss-Seidel from x = 0: only the lower triangle meets nonzero x.
  for (int i = 0; i < n; ++i) {
    Vec<dim> s = Cv<dim>(b + i * dim);
    for (int p = lp[i]; p < lp[i + 1]; ++p) s -= lv[p] * Cv<dim>(x + lc[p] * dim);
    Mv<dim>(x + i * dim) = dinv[i] * s;
  }
  // Restricted residual: b - A x = -U x after that sweep (the diagonal and lower parts cancel
  // b exactly), so r_c = P^T (-U x), with the fine residual formed row by row on the fly.
  double* bc = m_b[l].data();
  m_b[l].setZero();
  const int *pp = L.prolong.ptr.data(), *pc = L.prolong.col.data();
  const double* pv = L.prolong.val.data();
  for (int i = 0; i < n; ++i) {
    Vec<dim> r = Vec<dim>::Zero();
    for (int p = up[i]; p < up[i + 1]; ++p) r -= uv[p] * Cv<dim>(x + uc[p] * dim);
    for (int p = pp[i]; p < pp[i + 1]; ++p) Mv<dim>(bc + pc[p] * dim) += pv[p] * r;
  }
  double* xc = m_x[l].data();
  cycle(l + 1, bc, xc);
  // Prolongate (gather by P's rows), then backward Gauss-Seidel with the whole matrix.
  for (int i = 0; i < n; ++i) {
    Vec<dim> s = Cv<dim>(x + i * dim);
    for (int p = pp[i]; p < pp[i + 1]; ++p) s += pv[p] * Cv<dim>(xc + pc[p] * dim);
    Mv<dim>(x + i * dim) = s;
  }
  for (int i = n - 1; i >= 0; --i) {
    Vec<dim> s = Cv<dim>(b + i * dim);
    for (int p = lp[i]; p < lp[i + 1]; ++p) s -= lv[p] * Cv<dim>(x + lc[p] * dim);
    for (int p = up[i]; p < up[i + 1]; ++p) s -= uv[p] * Cv<dim>(x + uc[p] * dim);
    Mv<dim>(x + i * dim) = dinv[i] * s;
  }
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
  return bytes;
}

template class SymmetricMultigrid<2>;
template class SymmetricMultigrid<3>;

} // namespace vtb
