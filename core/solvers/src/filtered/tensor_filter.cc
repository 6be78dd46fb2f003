#include "vtb/solvers/tensor_filter.hh"

#include "mismatch_kernel.hh"
#include "polar_kernel.hh"

#include "vtb/springs/force_jacobian.hh"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vtb {

namespace {

/// A spring's transverse scale dt c + dt^2 k, k and c its constants (at rest the traces of its
/// blocks K = k n n^T and D = c n n^T).
double transverse_scale(double k, double c, double dt) {
  return dt * c + dt * dt * k;
}

/// A spring block's transverse part at beta = 1: scale (I - n n^T), n the spring's direction;
/// scale = -sign transverse_scale with the block's stiffness sign (+ on its diagonal blocks).
template <int dim> Mat<dim> transverse_block(double scale, const Vec<dim>& n) {
  return scale * (Mat<dim>::Identity() - n * n.transpose());
}

/// The unit direction of x_j - x_i (zero for a spring of length 0).
template <int dim> Vec<dim> direction(const Vec<dim>& xi, const Vec<dim>& xj) {
  const Vec<dim> d = xj - xi;
  const double l = d.norm();
  return l > 0 ? Vec<dim>(d / l) : Vec<dim>::Zero();
}

} // namespace

template <int dim>
Eigen::SparseMatrix<double> tensor_filter_matrix(const Model<dim>& model, double dt, double transverse) {
  const auto& net = model.net;
  const int nf = static_cast<int>(model.free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int a = 0; a < nf; ++a)
    for (int p = 0; p < dim; ++p)
      trip.emplace_back(a * dim + p, a * dim + p,
                        net.mass[model.free_nodes[static_cast<std::size_t>(a)]] * (1.0 + dt * net.mass_damping));
  // The shared assembly at rest: blocks k n n^T and c n n^T (-sign: stiffness signs), plus
  // `transverse` times their transverse parts k (I - n n^T) and c (I - n n^T). Every entry of
  // every block is stored, so the pattern does not depend on the values.
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_jacobian_block(
      net, rest, false, [&](int s, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
        const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
        if (a < 0 || b < 0) return;
        const auto& e = net.edge[static_cast<std::size_t>(s)];
        const Vec<dim> n = direction<dim>(net.rest.col(e[0]), net.rest.col(e[1]));
        const Mat<dim> B = -sign * (dt * D + dt * dt * K) +
                           transverse * transverse_block<dim>(-sign * transverse_scale(K.trace(), D.trace(), dt), n);
        for (int p = 0; p < dim; ++p)
          for (int q = 0; q < dim; ++q) trip.emplace_back(a * dim + p, b * dim + q, B(p, q));
      });
  Eigen::SparseMatrix<double> H(nf * dim, nf * dim);
  H.setFromTriplets(trip.begin(), trip.end());
  return H;
}

namespace {

/// The largest direction mismatch |d/|d| - t/|t|| over pairs (d, t): a spring's current
/// vector d and its rest vector turned by both ends' rotations, t = (R_i + R_j) D (their
/// mean: a smooth rotation field, bending, then leaves no mismatch, a distortion, shear,
/// which turns springs apart, does). |d/|d| - t/|t|| = 2 sin(theta / 2), theta the angle
/// between d and t: below 90 degrees the largest mismatch is the largest sin^2 theta =
/// |d x t|^2 / (|d|^2 |t|^2), scale-free in t (no rest direction to normalise) and with no
/// square root per spring (the step's cost: docs/performance.md); value() makes the mismatch
/// from it once. NaN propagates.
struct MismatchTracker {
  double worst_sin2 = 0, worst = 0;

  /// Adds the pair; true when its sin^2 passes `trigger` (or it is at 90 degrees or more).
  template <int dim> [[gnu::always_inline]] bool add(const Vec<dim>& d, const Vec<dim>& t, double trigger = 2.0) {
    double cross2;
    if constexpr (dim == 2) {
      cross2 = d.x() * t.y() - d.y() * t.x();
      cross2 *= cross2;
    } else {
      cross2 = d.cross(t).squaredNorm();
    }
    return add_terms(d.dot(t), cross2, d.squaredNorm() * t.squaredNorm(), trigger);
  }

  /// The same from the pair's d . t, |d x t|^2 and |d|^2 |t|^2 (`den`; a pair with den 0 is
  /// skipped, as a spring of length 0 has no direction).
  [[gnu::always_inline]] bool add_terms(double dot, double cross2, double den, double trigger) {
    if (!(den > 0)) return false;
    if (dot > 0) {
      // Divided only where a new worst is found (the divider stalled the loop); NaN stays.
      if (!(cross2 <= worst_sin2 * den)) {
        const double s2 = cross2 / den;
        worst_sin2 = std::isnan(worst_sin2) ? worst_sin2 : s2;
      }
      return cross2 > trigger * den;
    }
    // 90 degrees or more (at least sqrt(2)), or not finite: rare, directly as
    // |d/|d| - t/|t|| = sqrt(2 - 2 cos theta)
    const double m = std::sqrt(2 - 2 * dot / std::sqrt(den));
    if (!(m <= worst)) worst = m;
    return true;
  }

  /// The mismatch 2 sin(theta / 2) of a pair whose sin^2 theta is s2 (theta below 90 degrees).
  static double from_sin2(double s2) {
    s2 = std::min(s2, 1.0);
    return std::sqrt(2 * s2 / (1 + std::sqrt(1 - s2)));
  }
  /// The sin^2 theta of a mismatch m = 2 sin(theta / 2) <= sqrt(2): m^2 (1 - m^2 / 4).
  static double to_sin2(double m) { return m * m * (1 - m * m / 4); }

  double value() const {
    // 2 sin(theta / 2) = sqrt(2 - 2 cos theta) = sqrt(2 sin^2 / (1 + cos)), cos = sqrt(1 - sin^2).
    const double from_sin = from_sin2(worst_sin2);
    return std::isnan(worst_sin2) || std::isnan(worst) ? std::numeric_limits<double>::quiet_NaN()
                                                       : std::max(worst, from_sin);
  }
};

} // namespace

template <int dim>
TensorFilter<dim>::TensorFilter(const Model<dim>& model, double dt, bool multigrid)
    : m_model(model), m_rotation(dim == 3 ? static_cast<std::size_t>(model.num_nodes()) : 0, Mat<dim>::Identity()),
      m_capacitance(kMaxCoupled * dim) {
  const auto nf = static_cast<Eigen::Index>(model.free_nodes.size());
  Nodal<dim> x(dim, nf); // the free nodes' rest positions: the V-cycle's rigid modes
  for (Eigen::Index a = 0; a < nf; ++a) x.col(a) = model.net.rest.col(model.free_nodes[static_cast<std::size_t>(a)]);
  const Eigen::SparseMatrix<double> H0 = tensor_filter_matrix(model, dt, 0.0);
  m_h = make_warped_system<dim>(H0, x, multigrid);
  m_next = m_h->twin(H0); // the refreshes' (same ordering and pattern)
  m_index.resize(static_cast<std::size_t>(nf) * dim);
  for (int r = 0; r < static_cast<int>(nf) * dim; ++r) {
    m_index[static_cast<std::size_t>(r)] = m_h->index(r);
    if (m_index[static_cast<std::size_t>(r)] != m_index[static_cast<std::size_t>(r - r % dim)] + r % dim)
      throw std::logic_error("TensorFilter: the system does not keep a node's values consecutive");
    if (m_next->index(r) != m_index[static_cast<std::size_t>(r)])
      throw std::logic_error("TensorFilter: the two systems order the dofs differently");
  }
  if (m_next->value_count() != m_h->value_count())
    throw std::logic_error("TensorFilter: the two systems store different patterns");
  // Per node position in the solve's vector, its node and free index (what solve_turned reads;
  // meaningful where the system keeps a node's values at a multiple of dim, as the factor does).
  m_node_at.assign(static_cast<std::size_t>(m_h->size() / dim), -1);
  m_slot_at.assign(m_node_at.size(), -1);
  for (int a = 0; a < static_cast<int>(nf); ++a) {
    const int at = m_index[static_cast<std::size_t>(a) * dim];
    if (at % dim != 0 || at / dim >= static_cast<int>(m_node_at.size())) continue;
    m_node_at[static_cast<std::size_t>(at / dim)] = model.free_nodes[static_cast<std::size_t>(a)];
    m_slot_at[static_cast<std::size_t>(at / dim)] = a;
  }
  m_rhs = Eigen::MatrixXd::Zero(m_h->size(), 1);
  m_z = Eigen::MatrixXd::Zero(m_h->size(), kMaxCoupled * dim);
  m_base.assign(m_h->values(), m_h->values() + m_h->value_count());
  // Each spring's transverse blocks at beta = 1, (dt c + dt^2 k)(I - n n^T) with the signs of
  // tensor_filter_matrix, as (offset, value) pairs into H's stored values, so that H(beta)
  // = H(0) + sum_s beta_s T_s is refilled spring by spring. Every stored entry of a spring's
  // blocks is kept (with its block and place, m_tcode), zeros included: relinearize() writes
  // the blocks of another shape, whose zeros are elsewhere, at the same offsets.
  const auto& net = model.net;
  const int ns = net.num_springs();
  m_dt = dt;
  m_diag_off.resize(static_cast<std::size_t>(nf) * dim);
  for (int r = 0; r < static_cast<int>(nf) * dim; ++r) m_diag_off[static_cast<std::size_t>(r)] = m_h->offset(r, r);
  m_tptr.assign(static_cast<std::size_t>(ns) + 1, 0);
  m_tscale.assign(static_cast<std::size_t>(ns), 0.0);
  m_tdir = Nodal<dim>::Zero(dim, ns);
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_jacobian_block(
      net, rest, false, [&](int sp, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
        const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
        if (a >= 0 && b >= 0) {
          const auto& e = net.edge[static_cast<std::size_t>(sp)];
          const int block = (sign < 0 ? 0 : 2) + (i == e[0] ? 0 : 1); // (i,i), (j,j), (i,j), (j,i)
          // T's scale and direction (the same from each of the spring's blocks).
          m_tscale[static_cast<std::size_t>(sp)] = transverse_scale(K.trace(), D.trace(), dt);
          m_tdir.col(sp) = direction<dim>(net.rest.col(e[0]), net.rest.col(e[1]));
          for (int p = 0; p < dim; ++p)
            for (int q = 0; q < dim; ++q) {
              const long off = m_h->offset(a * dim + p, b * dim + q);
              if (off < 0) continue;
              m_toff.push_back(static_cast<int>(off));
              m_tcode.push_back(static_cast<unsigned char>((block * dim + p) * dim + q));
            }
        }
        m_tptr[static_cast<std::size_t>(sp) + 1] = static_cast<int>(m_toff.size());
      });
  m_trigger.assign(static_cast<std::size_t>(ns), MismatchTracker::to_sin2(kCoverFloor));
  m_beta.assign(static_cast<std::size_t>(ns), 0.0);
  m_spring_rest.resize(dim, ns);
  for (int sp = 0; sp < ns; ++sp)
    m_spring_rest.col(sp) = net.rest.col(net.edge[static_cast<std::size_t>(sp)][1]) -
                            net.rest.col(net.edge[static_cast<std::size_t>(sp)][0]);
  m_spring_ref = m_spring_rest;
  if constexpr (dim == 3) {
    m_adj_rest.resize(dim, static_cast<Eigen::Index>(net.adj_node.size()));
    for (int i = 0; i < net.num_nodes(); ++i)
      for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p)
        m_adj_rest.col(p) = net.rest.col(net.adj_node[static_cast<std::size_t>(p)]) - net.rest.col(i);
    // Per node 3 / sum |X_j - X_i|^2 = 3 / tr A_rest: A scaled by it has singular values near 1
    // (its polar factor unchanged), where the polar iteration needs few steps.
    m_adj_ref = m_adj_rest;
    m_adj_ref_next = m_adj_rest;
    m_adj_scale.assign(static_cast<std::size_t>(net.num_nodes()), 1.0);
    m_adj_scale_next = m_adj_scale;
    m_polar_a.assign(9 * static_cast<std::size_t>(net.num_nodes()), 0.0);
    m_polar_ok.assign(static_cast<std::size_t>(net.num_nodes()), 0);
    scale_neighbourhoods(m_adj_ref, m_adj_scale);
  }
  m_spring_ref_next = m_spring_ref;
  m_tscale_next = m_tscale;
  m_tdir_next = m_tdir;
  m_multigrid = multigrid;
  m_residual = Nodal<dim>::Zero(dim, net.num_nodes());
  m_iterate = Nodal<dim>::Zero(dim, net.num_nodes());
  m_direction = Nodal<dim>::Zero(dim, nf);
  m_search = Nodal<dim>::Zero(dim, nf);
  m_product = Nodal<dim>::Zero(dim, net.num_nodes());
  m_spring_d.resize(dim, ns);
  m_spring_q.resize(ns);
  m_spring_at.resize(ns);
  if constexpr (dim == 2) {
    m_polar.resize(2, net.num_nodes());
    m_pq.resize(ns, 2);
  }
}

template <int dim>
template <class Tracker>
[[gnu::always_inline]] inline bool TensorFilter<dim>::add_spring(Tracker& tracker, int s, const Nodal<dim>& u,
                                                                 double trigger) const {
  const auto [i, j] = m_model.net.edge[static_cast<std::size_t>(s)];
  const Vec<dim> D = m_spring_ref.col(s);
  Vec<dim> t;
  if constexpr (dim == 2) {
    // (R_i + R_j) D from the rotations as (cos, sin) (m_polar after rotations()): half the
    // bytes per end of a 2 x 2 matrix.
    const Vec<2> cs = m_polar.col(i) + m_polar.col(j);
    t = Vec<2>(cs.x() * D.x() - cs.y() * D.y(), cs.y() * D.x() + cs.x() * D.y());
  } else {
    t = (rotation(i) + rotation(j)) * D;
  }
  return tracker.template add<dim>(m_spring_rest.col(s) + u.col(j) - u.col(i), t, trigger);
}

template <int dim> double TensorFilter<dim>::scan(const Nodal<dim>& u, bool* outgrown) const {
  MismatchTracker worst;
  bool out = false;
  const int ns = m_model.net.num_springs();
  if constexpr (dim == 2) {
    // From the springs' products that rotations() left in m_pq (p = d . D, q = D x d, so that
    // p^2 + q^2 = |d|^2 |D|^2) and the ends' (cos, sin) summed, c: with t = (R_i + R_j) D and
    // R_i + R_j = [cx -cy; cy cx], d . t = cx p + cy q, d x t = cy p - cx q and |t|^2 = |c|^2
    // |D|^2, so u is not read again. The rare spring past 90 degrees (or of length 0, or not
    // finite) sends the scan to the tracker's exact pass.
    (void)u;
    bool rare = false;
    const auto& edge = m_model.net.edge;
    const double sin2 =
        detail::largest_sin2(ns, &m_pq(0, 0), &m_pq(0, 1), edge.data(), m_polar.data(), m_trigger.data(), out, rare);
    if (!rare) {
      if (outgrown) *outgrown = out;
      return MismatchTracker::from_sin2(sin2);
    }
    out = false;
    for (int s = 0; s < ns; ++s) {
      const auto [i, j] = edge[static_cast<std::size_t>(s)];
      const double p = m_pq(s, 0), q = m_pq(s, 1), cx = m_polar(0, i) + m_polar(0, j),
                   cy = m_polar(1, i) + m_polar(1, j);
      const double cross = cy * p - cx * q;
      out |= worst.add_terms(cx * p + cy * q, cross * cross, (p * p + q * q) * (cx * cx + cy * cy),
                             m_trigger[static_cast<std::size_t>(s)]);
    }
  } else {
    // Four springs per vector (detail::largest_sin2_3d); the rare spring past 90 degrees (or of
    // length 0, or not finite) sends the scan to the tracker's exact pass, as in 2D.
    bool rare = false;
    const double sin2 = detail::largest_sin2_3d(ns, m_model.net.edge.data(), m_spring_rest.data(), m_spring_ref.data(),
                                                u.data(), m_rotation.data()->data(), m_trigger.data(), out, rare);
    if (!rare) {
      if (outgrown) *outgrown = out;
      return MismatchTracker::from_sin2(sin2);
    }
    out = false;
    for (int s = 0; s < ns; ++s) out |= add_spring(worst, s, u, m_trigger[static_cast<std::size_t>(s)]);
  }
  if (outgrown) *outgrown = out;
  return worst.value();
}

template <int dim> double TensorFilter<dim>::direction_mismatch(const Nodal<dim>& u) const {
  return scan(u, nullptr);
}

template <int dim> double TensorFilter<dim>::spring_mismatch(int s, const Nodal<dim>& u) const {
  MismatchTracker one;
  add_spring(one, s, u, 2.0);
  return one.value();
}

template <int dim> void TensorFilter<dim>::cover(const Nodal<dim>& u, double mismatch, bool at_once) {
  // Each spring's beta is twice its own mismatch while the largest, M, is at most
  // kLocalCoverLimit; past it every spring gets the largest, 2 M. Kept until a spring outgrows
  // its beta or M falls 8x below the largest; no cover at all while M < kCoverFloor (the
  // lag-free filter). Measured (docs/method.md): half the cover diverges on the paper's plate at
  // a tenth of its stiffness, twice it doubles the cantilever's error at 40 ms; one beta for the
  // whole mesh at every M took a slab pressed at one point to 3.9x implicit Euler's error (each
  // spring's own: 1.04x), each spring's own at every M folded the plate under four forces at a
  // tenth of its stiffness (strains past 0.1 turn springs that had little mismatch within a step).
  const auto& net = m_model.net;
  const double global = mismatch < kCoverFloor ? 0.0 : std::min(1.0, 2 * mismatch);
  for (int s = 0; s < net.num_springs(); ++s) {
    const double b = global == 0                   ? 0.0
                     : mismatch > kLocalCoverLimit ? global
                                                   : std::min(global, 2 * spring_mismatch(s, u));
    m_beta[static_cast<std::size_t>(s)] = b;
    m_trigger[static_cast<std::size_t>(s)] = MismatchTracker::to_sin2(std::max(b, kCoverFloor));
  }
  m_beta_max = global;
  start_refresh(false);
  if (at_once) finish_refresh();
}

template <int dim> void TensorFilter<dim>::start_refresh(bool relinearized) {
  // H(beta) = H(0) + sum_s beta_s T_s into the second system's values, from the H(0) and T of
  // the reference shape it will have (a relinearisation's, or the one in use).
  const auto& net = m_model.net;
  double* v = m_next->values();
  if (!relinearized) std::copy(m_base.begin(), m_base.end(), v); // a relinearisation wrote its H(0) there
  if (!relinearized)                                             // a relinearisation starts with no cover
    for (int s = 0; s < net.num_springs(); ++s) {
      const double b = m_beta[static_cast<std::size_t>(s)];
      if (b == 0) continue;
      const Mat<dim> T = transverse_block<dim>(m_tscale[static_cast<std::size_t>(s)], m_tdir.col(s));
      for (int k = m_tptr[static_cast<std::size_t>(s)]; k < m_tptr[static_cast<std::size_t>(s) + 1]; ++k) {
        const int code = m_tcode[static_cast<std::size_t>(k)];
        const double t = T((code / dim) % dim, code % dim);
        v[m_toff[static_cast<std::size_t>(k)]] += b * (code / (dim * dim) < 2 ? t : -t); // - on (i,j), (j,i)
      }
    }
  m_next->begin_refresh();
  m_refresh_done = 0;
  m_refreshing = true;
  m_next_relinearized = relinearized;
}

template <int dim> void TensorFilter<dim>::advance_refresh(double mismatch) {
  if (!m_refreshing) return;
  // 1 / kRefreshParts of the work; more where a relinearisation would not be done before the
  // mismatch, growing as it did over the last step, reaches kHardMismatch: what is left spread
  // over the steps left (so that the work per step grows smoothly instead of one step carrying
  // the rest at the hard limit).
  double share = 1.0 / kRefreshParts;
  const double growth = mismatch - m_last_mismatch;
  if (m_next_relinearized && growth > 0 && mismatch < kHardMismatch) {
    const double steps_left = std::max(1.0, (kHardMismatch - mismatch) / growth - 1);
    share = std::max(share, (1 - m_refresh_done) / steps_left);
  }
  m_last_mismatch = mismatch;
  m_refresh_done += share;
  if (m_next->refresh_part(share)) swap_systems();
}

template <int dim> void TensorFilter<dim>::finish_refresh() {
  if (!m_refreshing) return;
  if (!m_next->refresh_part(1.0 / kRefreshParts)) { // more than one part left
    ++m_refreshes_at_once;
    while (!m_next->refresh_part(1.0)) {
    }
  }
  swap_systems();
}

template <int dim> void TensorFilter<dim>::swap_systems() {
  std::swap(m_h, m_next);
  if (m_next_relinearized) { // the new reference shape, with no cover on it
    m_spring_ref.swap(m_spring_ref_next);
    m_adj_ref.swap(m_adj_ref_next);
    m_adj_scale.swap(m_adj_scale_next);
    std::copy(m_h->values(), m_h->values() + m_base.size(), m_base.begin()); // its H(0) (refreshes leave values)
    m_tscale.swap(m_tscale_next);
    m_tdir.swap(m_tdir_next);
    std::fill(m_beta.begin(), m_beta.end(), 0.0);
    std::fill(m_trigger.begin(), m_trigger.end(), MismatchTracker::to_sin2(kCoverFloor));
    m_beta_max = 0;
    ++m_relinearizations;
  }
  m_refreshing = false;
  m_next_relinearized = false;
  m_correction_rest = 0; // a new H: correct() measures its gain again
  ++m_factor_version;
}

template <int dim> void TensorFilter<dim>::relinearize(const Nodal<dim>& u, bool at_once) {
  // H = M (1 + dt gamma) + dt D(u) + dt^2 K(u) at the shape X + u (K's transverse term clamped
  // at 0 under compression, as implicit Euler's, so that H stays positive definite), written
  // at the offsets the constructor kept; the transverse blocks and the reference vectors of
  // that shape, all into the second system's arrays (the ones in use serve the steps until it
  // takes over); no cover. Allocates nothing.
  const auto& net = m_model.net;
  const auto& free = m_model.free_nodes;
  const double dt = m_dt;
  double* base = m_next->values(); // H(0) of that shape, with no cover
  std::fill_n(base, m_next->value_count(), 0.0);
  for (std::size_t r = 0; r < m_diag_off.size(); ++r)
    base[static_cast<std::size_t>(m_diag_off[r])] += net.mass[free[r / dim]] * (1.0 + dt * net.mass_damping);
  for (int s = 0; s < net.num_springs(); ++s) {
    const auto [i, j] = net.edge[static_cast<std::size_t>(s)];
    const Vec<dim> xi = net.rest.col(i) + u.col(i), xj = net.rest.col(j) + u.col(j);
    m_spring_ref_next.col(s) = xj - xi;
    const int begin = m_tptr[static_cast<std::size_t>(s)], end = m_tptr[static_cast<std::size_t>(s) + 1];
    if (begin == end) continue;
    const double k = net.stiffness[static_cast<std::size_t>(s)], c = net.damping[static_cast<std::size_t>(s)];
    const Mat<dim> B = dt * dashpot_jacobian<dim>(xi, xj, c) +
                       dt * dt * spring_jacobian<dim>(xi, xj, net.rest_length[static_cast<std::size_t>(s)], k, true);
    m_tscale_next[static_cast<std::size_t>(s)] = transverse_scale(k, c, dt); // the transverse blocks of this shape
    m_tdir_next.col(s) = direction<dim>(xi, xj);
    for (int e = begin; e < end; ++e) {
      const int code = m_tcode[static_cast<std::size_t>(e)];
      const int p = (code / dim) % dim, q = code % dim;
      const double sign = code / (dim * dim) < 2 ? 1.0 : -1.0; // H's sign: + on (i,i), (j,j)
      base[static_cast<std::size_t>(m_toff[static_cast<std::size_t>(e)])] += sign * B(p, q);
    }
  }
  if constexpr (dim == 3)
    for (int i = 0; i < net.num_nodes(); ++i)
      for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p)
        m_adj_ref_next.col(p) = m_adj_rest.col(p) + u.col(net.adj_node[static_cast<std::size_t>(p)]) - u.col(i);
  scale_neighbourhoods(m_adj_ref_next, m_adj_scale_next);
  start_refresh(true);
  if (at_once) finish_refresh();
}

template <int dim> double TensorFilter<dim>::prepare(const Nodal<dim>& u) {
  rotations(u);
  return follow(u);
}

template <int dim> double TensorFilter<dim>::prepare_turned(const Nodal<dim>& u) {
  turn_rotations();
  return follow(u);
}

template <int dim> double TensorFilter<dim>::follow(const Nodal<dim>& u) {
  bool outgrown = false;
  const double mismatch = scan(u, &outgrown);
  if (!(mismatch <= kTrustedMismatch) || m_refreshing) return mismatch; // one refresh at a time
  if (outgrown || 8 * mismatch < m_beta_max) cover(u, mismatch, false);
  return mismatch;
}

template <int dim>
void TensorFilter<dim>::solve(const Nodal<dim>& force, const CouplingSet<dim>& couplings, double dt, Nodal<dim>& dv) {
  couple(couplings);
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<int>(free.size());
  // Each node's dim values sit together in the solve's vector, from m_index[dim a] on (both
  // systems keep a node's values consecutive); raw pointers, so that no store makes the loop
  // reload a vector's data pointer.
  double* __restrict y = m_rhs.data();
  const int* __restrict at = m_index.data();
  if constexpr (dim == 2) {
    // The factor turns the values into and out of its sweeps (out of them only without
    // couplings, whose correction comes between the solve and the turn out).
    if (m_h->solve_turned(force.data(), m_polar.data(), m_node_at.data(), m_slot_at.data(), dt, y,
                          m_coupled == 0 ? dv.data() : nullptr)) {
      if (m_coupled == 0) return;
      correct_for_couplings(m_rhs);
      turn_out(dt, dv);
      return;
    }
  }
  for (int a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    const Vec<dim> f = rotation(i).transpose() * force.col(i);
    for (int p = 0; p < dim; ++p) y[at[a * dim] + p] = f[p];
  }
  m_h->solve(m_rhs.col(0));
  correct_for_couplings(m_rhs);
  turn_out(dt, dv);
}

template class TensorFilter<2>;
template class TensorFilter<3>;
template Eigen::SparseMatrix<double> tensor_filter_matrix<2>(const Model<2>&, double, double);
template Eigen::SparseMatrix<double> tensor_filter_matrix<3>(const Model<3>&, double, double);

} // namespace vtb
