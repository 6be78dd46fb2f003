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

} // namespace

template <int dim>
void add_internal_forces(const SpringNetwork<dim>& net, const Nodal<dim>& u, const Nodal<dim>& v, Nodal<dim>& f,
                         double extra_damping_per_k) {
  const int ns = net.num_springs();
  const auto* e = net.edge.data();
  alignas(64) double d[kChunk * dim], l2[kChunk], dot[kChunk], g[kChunk];
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
    voigt_coefficients(n, l2, dot, net.rest_length.data() + s0, net.stiffness.data() + s0, net.damping.data() + s0,
                       extra_damping_per_k, g);
    // Scatter, node i's force summed over its run of springs (add_by_first_node_runs).
    add_by_first_node_runs<-1>(net, s0, n, f,
                               [&](int s) -> Vec<dim> { return g[s] * Eigen::Map<const Vec<dim>>(d + dim * s); });
  }
  if (net.mass_damping != 0) f.noalias() -= net.mass_damping * (v * net.mass.asDiagonal());
}

template void add_internal_forces<2>(const SpringNetwork<2>&, const Nodal<2>&, const Nodal<2>&, Nodal<2>&, double);
template void add_internal_forces<3>(const SpringNetwork<3>&, const Nodal<3>&, const Nodal<3>&, Nodal<3>&, double);

} // namespace vtb
