// TensorFilter::correct: one step of conjugate gradients on implicit Euler's system,
// preconditioned by the tensor filter itself (docs/method.md, "The step corrected toward
// implicit Euler's"). Its spring passes are laid out as the spring kernel's (spring_forces.cc):
// a gather per chunk of springs, the per-spring arithmetic in one vector loop, a scatter that
// sums each first node's run in registers.
#include "vtb/solvers/tensor_filter.hh"

#include "vtb/linalg/vector_clones.hh"
#include "vtb/springs/spring_kernels.hh"

#include <algorithm>
#include <cmath>

namespace vtb {
namespace {

/// Springs per chunk: the chunk's scratch stays in L1 and on the stack.
constexpr int kChunk = 256;

/// Per spring, from l^2 = |d|^2, d . w and d . e (d the spring's vector, w = x_i - x_j the
/// iterate's difference, e = v_j - v_i): the residual's term t = g d + a_t (e - w), and A's
/// block B = a_n n n^T + a_t (I - n n^T) = q d d^T + a_t I kept as (q, a_t) for z . A z. Here
/// a_n = dt c + dt^2 k and a_t = dt^2 k max(0, 1 - L0 / l) (implicit Euler's Jacobian, its
/// transverse term clamped under compression); zero where l = 0 or l is NaN. No gather, no
/// branch: the loop vectorises.
VTB_VECTOR_CLONES void correction_terms(int n, double dt, const double* __restrict l2, const double* __restrict dw,
                                        const double* __restrict de, const double* __restrict rest_length,
                                        const double* __restrict k, const double* __restrict c, double* __restrict g,
                                        double* __restrict q, double* __restrict a_t) {
  // __restrict: three outputs against six inputs are more pairs than GCC checks for aliasing
  // at run time (10), and it would not vectorise.
  const double dt2 = dt * dt;
  for (int s = 0; s < n; ++s) {
    const double inv_l = newton_inverse_sqrt(l2[s]), inv_l2 = inv_l * inv_l;
    const double a_n = dt * c[s] + dt2 * k[s];
    const double stretch = 1.0 - rest_length[s] * inv_l;
    const double t = stretch > 0 ? dt2 * k[s] * stretch : 0.0;
    const double qs = (a_n - t) * inv_l2;
    const bool live = l2[s] > 0;
    g[s] = live ? -qs * dw[s] - t * inv_l2 * de[s] : 0.0;
    q[s] = live ? qs : 0.0;
    a_t[s] = live ? t : 0.0;
  }
}

/// Node i's diagonal in implicit Euler's matrix A: its lumped mass with the mass-proportional
/// damping's dt term, m_i (1 + dt gamma).
template <int dim> double mass_diagonal(const SpringNetwork<dim>& net, int i, double dt) {
  return net.mass[i] * (1.0 + dt * net.mass_damping);
}

} // namespace

template <int dim>
void TensorFilter<dim>::correct(const Nodal<dim>& u, const Nodal<dim>& v, const Nodal<dim>& force,
                                const CouplingSet<dim>& couplings, double dt, Nodal<dim>& dv) {
  if (!(m_multigrid || m_beta_max > 0)) return; // H is the warped rest Jacobian: nothing to correct
  if (m_correction_rest > 0) {
    --m_correction_rest;
    return;
  }
  const auto& net = m_model.net;
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<Eigen::Index>(free.size());
  const int ns = net.num_springs();
  const auto* e = net.edge.data();
  // r = b - A x at x = dv: b = dt F' plus the transverse part of dt^2 K v (F' holds its axial
  // part, the filter's dt k term), A x = the mass's, the couplings' c w w^T x and the springs'
  // B (x_i - x_j).
  // e0 = x . A x, the step's own energy, for the gain below (which the V-cycle does not read).
  m_iterate.setZero();
  m_residual = dt * force;
  double e0 = 0;
  for (Eigen::Index a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    const double m = mass_diagonal(net, i, dt);
    m_iterate.col(i) = dv.col(a);
    m_residual.col(i) -= m * dv.col(a);
    e0 += m * dv.col(a).squaredNorm();
  }
  e0 += couplings.subtract_product(m_iterate, m_residual);
  alignas(64) double ew[kChunk * dim], l2[kChunk], dw[kChunk], de[kChunk], ww[kChunk], g[kChunk];
  for (int s0 = 0; s0 < ns; s0 += kChunk) {
    const int n = std::min(kChunk, ns - s0);
    for (int s = 0; s < n; ++s) {
      const int i = e[s0 + s][0], j = e[s0 + s][1];
      const Vec<dim> ds = net.rest.col(j) + u.col(j) - net.rest.col(i) - u.col(i);
      const Vec<dim> w = m_iterate.col(i) - m_iterate.col(j), vel = v.col(j) - v.col(i);
      m_spring_d.col(s0 + s) = ds;
      Eigen::Map<Vec<dim>>(ew + dim * s) = vel - w;
      l2[s] = ds.squaredNorm();
      dw[s] = ds.dot(w);
      de[s] = ds.dot(vel);
      ww[s] = w.squaredNorm();
    }
    correction_terms(n, dt, l2, dw, de, net.rest_length.data() + s0, net.stiffness.data() + s0, net.damping.data() + s0,
                     g, m_spring_q.data() + s0, m_spring_at.data() + s0);
    for (int s = 0; s < n; ++s) e0 += m_spring_q[s0 + s] * dw[s] * dw[s] + m_spring_at[s0 + s] * ww[s];
    add_by_first_node_runs<-1>(net, s0, n, m_residual, [&](int s) -> Vec<dim> {
      return g[s] * m_spring_d.col(s0 + s) + m_spring_at[s0 + s] * Eigen::Map<const Vec<dim>>(ew + dim * s);
    });
  }
  // z = P r (P: R H'^-1 R^T, this filter's own solve), alpha = r . z / z . A z.
  solve(m_residual, couplings, 1.0, m_direction);
  double rz = 0, zaz = 0;
  for (Eigen::Index a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    m_iterate.col(i) = m_direction.col(a);
    rz += m_residual.col(i).dot(m_direction.col(a));
    zaz += mass_diagonal(net, i, dt) * m_direction.col(a).squaredNorm();
  }
  zaz += couplings.energy(m_iterate);
  for (int s = 0; s < ns; ++s) {
    const Vec<dim> w = m_iterate.col(e[s][0]) - m_iterate.col(e[s][1]);
    const double dws = m_spring_d.col(s).dot(w);
    zaz += m_spring_q[s] * dws * dws + m_spring_at[s] * w.squaredNorm();
  }
  const double alpha = rz / zaz;
  if (!(zaz > 0) || !std::isfinite(alpha)) return; // nothing to gain (or a non-finite state: the run's watch)
  dv += alpha * m_direction;
  // The gain: the correction's share of the step in A's energy norm, (alpha z) . A (alpha z) /
  // x . A x = (r . z)^2 / (z . A z x . A x). Below kCorrectionGain a cover's step is close to
  // implicit Euler's, and the next kCorrectionRest steps go uncorrected. Under the V-cycle
  // every step is corrected: its extra mass Delta lags every step alike, and small gains add
  // up (a held-out slab press of 1,500 nodes at dt 1 ms: 1.54x implicit Euler's error with the
  // rest, 1.11x without; docs/method.md).
  double gain = rz * rz / (zaz * e0);
  if (!m_multigrid && gain < kCorrectionGain) m_correction_rest = kCorrectionRest;
  // Under the V-cycle, above kCorrectionStepGain the step is far from implicit Euler's (its
  // Delta at nu near 1/2): conjugate gradients go on from there, r -= alpha A p, p = z + beta
  // p, while each step's gain stays above it, kCorrectionSteps in all at most. (A cover's
  // departure is its transverse damping's lag, which one step takes up: the four-force plate
  // at 1.0x implicit Euler's error; docs/method.md.)
  if (!m_multigrid || gain <= kCorrectionStepGain) return;
  m_search = m_direction;
  minus_product(couplings, dt); // -A z (z in m_iterate): the sums above made no vector of it
  double rz_k = rz, alpha_k = alpha;
  for (int step = 1; step < kCorrectionSteps && gain > kCorrectionStepGain; ++step) {
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      m_residual.col(i) += alpha_k * m_product.col(i);
    }
    solve(m_residual, couplings, 1.0, m_direction);
    double rz_next = 0;
    for (Eigen::Index a = 0; a < nf; ++a)
      rz_next += m_residual.col(free[static_cast<std::size_t>(a)]).dot(m_direction.col(a));
    m_search = m_direction + (rz_next / rz_k) * m_search;
    for (Eigen::Index a = 0; a < nf; ++a) m_iterate.col(free[static_cast<std::size_t>(a)]) = m_search.col(a);
    const double pap = minus_product(couplings, dt);
    alpha_k = rz_next / pap;
    if (!(pap > 0) || !std::isfinite(alpha_k)) return;
    dv += alpha_k * m_search;
    gain = rz_next * rz_next / (pap * e0);
    rz_k = rz_next;
    ++m_extra_corrections;
  }
}

template <int dim> double TensorFilter<dim>::minus_product(const CouplingSet<dim>& couplings, double dt) {
  const auto& net = m_model.net;
  const auto& free = m_model.free_nodes;
  const auto* e = net.edge.data();
  const int ns = net.num_springs();
  double pap = 0;
  for (std::size_t a = 0; a < free.size(); ++a) {
    const int i = free[a];
    const double m = mass_diagonal(net, i, dt);
    m_product.col(i) = -m * m_iterate.col(i);
    pap += m * m_iterate.col(i).squaredNorm();
  }
  pap += couplings.subtract_product(m_iterate, m_product);
  for (int s0 = 0; s0 < ns; s0 += kChunk) {
    const int n = std::min(kChunk, ns - s0);
    add_by_first_node_runs<-1>(net, s0, n, m_product, [&](int s) -> Vec<dim> {
      const int k = s0 + s;
      const Vec<dim> w = m_iterate.col(e[k][0]) - m_iterate.col(e[k][1]);
      const double dws = m_spring_d.col(k).dot(w);
      pap += m_spring_q[k] * dws * dws + m_spring_at[k] * w.squaredNorm();
      return -(m_spring_q[k] * dws * m_spring_d.col(k) + m_spring_at[k] * w);
    });
  }
  return pap;
}

template void TensorFilter<2>::correct(const Nodal<2>&, const Nodal<2>&, const Nodal<2>&, const CouplingSet<2>&, double,
                                       Nodal<2>&);
template void TensorFilter<3>::correct(const Nodal<3>&, const Nodal<3>&, const Nodal<3>&, const CouplingSet<3>&, double,
                                       Nodal<3>&);

} // namespace vtb
