// add_internal_forces: the spring kernel of every integrator, in three passes per chunk of
// springs (gather, coefficients, scatter), so that the per-spring arithmetic runs on vector
// registers and without the divider (docs/performance.md: 5.2 -> 4.3 us on the 517-node plate).
#include "vtb/springs/spring_network.hh"

#include "vtb/linalg/vector_clones.hh"

#include <algorithm>

namespace vtb {
namespace {

/// Springs per chunk: the chunk's scratch (dim + 2 doubles a spring) stays in L1 and on the
/// stack, so the step allocates nothing.
constexpr int kChunk = 256;

/// g = (k (l - L0) + c (d . dv) / l) / l per spring, with c = damping + extra k, so that the
/// force on node i is g d (voigt_force's expression, with 1/l from newton_inverse_sqrt); zero
/// where l = 0 or l is NaN. No gather, no scatter: the loop vectorises.
VTB_VECTOR_CLONES void voigt_coefficients(int n, const double* l2, const double* dot, const double* rest_length,
                                          const double* k, const double* damping, double extra, double* g) {
  for (int s = 0; s < n; ++s) {
    const double inv_l = newton_inverse_sqrt(l2[s]);
    const double c = damping[s] + extra * k[s];
    const double value = (k[s] * (l2[s] * inv_l - rest_length[s]) + c * inv_l * dot[s]) * inv_l;
    g[s] = l2[s] > 0 ? value : 0.0;
  }
}

/// The springs' turns from their vectors d now (2 per spring) and D at rest: p = d . D, q = D
/// x d. No gather, no branch: the loop vectorises.
VTB_VECTOR_CLONES void turn_terms(int n, const double* __restrict d, const double* __restrict rest,
                                  double* __restrict p, double* __restrict q) {
  for (int s = 0; s < n; ++s) {
    const double dx = d[2 * s], dy = d[2 * s + 1], Dx = rest[2 * s], Dy = rest[2 * s + 1];
    p[s] = dx * Dx + dy * Dy;
    q[s] = Dx * dy - Dy * dx;
  }
}

/// The spring kernel, with the springs' turns (2D) where `turns` is given.
template <int dim>
void forces_kernel(const SpringNetwork<dim>& net, const Nodal<dim>& u, const Nodal<dim>& v, Nodal<dim>& f,
                   double extra_damping_per_k, const SpringTurns* turns) {
  const int ns = net.num_springs();
  const auto* e = net.edge.data();
  alignas(64) double d[kChunk * dim], l2[kChunk], dot[kChunk], g[kChunk];
  if constexpr (dim == 2)
    if (turns) turns->sums->setZero();
  for (int s0 = 0; s0 < ns; s0 += kChunk) {
    const int n = std::min(kChunk, ns - s0);
    // Gather: the spring's vector d = x_j - x_i and d . (v_j - v_i).
    int i = e[s0][0];
    Vec<dim> xi = net.rest.col(i) + u.col(i), vi = v.col(i);
    for (int s = 0; s < n; ++s) {
      if (e[s0 + s][0] != i) {
        i = e[s0 + s][0];
        xi = net.rest.col(i) + u.col(i);
        vi = v.col(i);
      }
      const int j = e[s0 + s][1];
      const Vec<dim> ds = (net.rest.col(j) + u.col(j)) - xi;
      Eigen::Map<Vec<dim>>(d + dim * s) = ds;
      l2[s] = ds.squaredNorm();
      dot[s] = ds.dot(v.col(j) - vi);
    }
    if constexpr (dim == 2)
      if (turns) turn_terms(n, d, turns->rest + 2 * s0, turns->p + s0, turns->q + s0);
    voigt_coefficients(n, l2, dot, net.rest_length.data() + s0, net.stiffness.data() + s0, net.damping.data() + s0,
                       extra_damping_per_k, g);
    // Scatter, node i's force summed over its run of springs (add_by_first_node_runs); with
    // the turns, their sums in the same run.
    if constexpr (dim == 2) {
      if (turns) {
        Eigen::Matrix2Xd& sums = *turns->sums;
        const double *p = turns->p + s0, *q = turns->q + s0;
        int a = e[s0][0];
        Vec<2> fa = Vec<2>::Zero(), ta = Vec<2>::Zero();
        for (int k = 0; k < n; ++k) {
          if (e[s0 + k][0] != a) {
            f.col(a) += fa;
            sums.col(a) += ta;
            a = e[s0 + k][0];
            fa.setZero();
            ta.setZero();
          }
          const int b = e[s0 + k][1];
          const Vec<2> t = g[k] * Eigen::Map<const Vec<2>>(d + 2 * k), pq(p[k], q[k]);
          fa += t;
          ta += pq;
          f.col(b) -= t;
          sums.col(b) += pq;
        }
        f.col(a) += fa;
        sums.col(a) += ta;
        continue;
      }
    }
    add_by_first_node_runs<-1>(net, s0, n, f,
                               [&](int s) -> Vec<dim> { return g[s] * Eigen::Map<const Vec<dim>>(d + dim * s); });
  }
  if (!net.volume.empty()) add_volume_forces(net.volume, net.rest, u, v, f, extra_damping_per_k);
  if (net.mass_damping != 0) f.noalias() -= net.mass_damping * (v * net.mass.asDiagonal());
}

} // namespace

template <int dim>
void add_internal_forces(const SpringNetwork<dim>& net, const Nodal<dim>& u, const Nodal<dim>& v, Nodal<dim>& f,
                         double extra_damping_per_k) {
  forces_kernel(net, u, v, f, extra_damping_per_k, nullptr);
}

void add_internal_forces_and_turns(const SpringNetwork<2>& net, const Nodal<2>& u, const Nodal<2>& v, Nodal<2>& f,
                                   double extra_damping_per_k, const SpringTurns& turns) {
  forces_kernel(net, u, v, f, extra_damping_per_k, &turns);
}

void spring_turns(const SpringNetwork<2>& net, const Nodal<2>& u, const SpringTurns& turns) {
  // The turns' own pass: each spring's (p, q) added to both ends (add_by_first_node_runs), by
  // turn_terms' expressions on d as the force kernel makes it, so both give the same turns.
  Eigen::Matrix2Xd& sums = *turns.sums;
  sums.setZero();
  add_by_first_node_runs<+1>(net, 0, net.num_springs(), sums, [&](int s) -> Vec<2> {
    const auto [i, j] = net.edge[static_cast<std::size_t>(s)];
    const Vec<2> d = (net.rest.col(j) + u.col(j)) - (net.rest.col(i) + u.col(i));
    turn_terms(1, d.data(), turns.rest + 2 * s, turns.p + s, turns.q + s);
    return Vec<2>(turns.p[s], turns.q[s]);
  });
}

template void add_internal_forces<2>(const SpringNetwork<2>&, const Nodal<2>&, const Nodal<2>&, Nodal<2>&, double);
template void add_internal_forces<3>(const SpringNetwork<3>&, const Nodal<3>&, const Nodal<3>&, Nodal<3>&, double);

} // namespace vtb
