#pragma once
/// \file
/// The virtual coupling between a device's handle and its proxy on the body, shared by the
/// haptics session's servo loop and the viewer's device mode.

#include "vtb/haptics/contact_result.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/springs/spring_kernels.hh"

#include <array>

namespace vtb {

/// The footprint's weighted mean of a nodal field, sum_p w_p x_p: the proxy's position (x the
/// nodes' positions) or its velocity (x their velocities).
template <int dim> Vec<dim> footprint_mean(const Footprint& fp, const Nodal<dim>& x) {
  Vec<dim> sum = Vec<dim>::Zero();
  for (std::size_t p = 0; p < static_cast<std::size_t>(fp.count); ++p) sum += fp.weight[p] * x.col(fp.node[p]);
  return sum;
}

/// A spring k (in series with the footprint's missing local compliance) between handle and proxy, and a damper b on
/// their relative velocity (the proxy moves with the surface: the weighted velocities of the footprint's nodes).
/// Contact pushes and never pulls: a negative normal part (the handle withdrawing faster than the surface follows) is
/// dropped, so the surface is not sticky. The force acts on the handle; the body receives its negative at the
/// footprint's nodes, by its weights (apply_to_body).
template <int dim>
Vec<dim> virtual_coupling(const ContactResult<dim>& c, const Vec<dim>& handle, const Vec<dim>& handle_velocity,
                          const Nodal<dim>& node_velocity, double k, double b) {
  const Footprint& fp = c.footprint;
  const Vec<dim> proxy_velocity = footprint_mean<dim>(fp, node_velocity);
  const Vec<dim> depth = c.proxy - handle;
  Vec<dim> f = tip_stiffness(k, fp) * depth + b * (proxy_velocity - handle_velocity);
  const double d2 = depth.squaredNorm();
  if (d2 > 0) {
    const double normal = f.dot(depth) / d2;
    if (normal < 0) f -= normal * depth;
  }
  return f;
}

/// A force alone on the footprint's nodes by their weights (no coupling for the solver).
template <int dim> void apply_force_to_body(const Footprint& fp, const Vec<dim>& force_on_body, State<dim>& s) {
  for (std::size_t p = 0; p < static_cast<std::size_t>(fp.count); ++p)
    s.applied.col(fp.node[p]) += fp.weight[p] * force_on_body;
}

/// A contact's force on the body at its footprint's nodes, by their weights w, and the
/// coupling's stiffness k (in series with the footprint's compliance) and damping b as w_i k
/// and w_i b in one coupling group (its
/// Jacobian k w w^T: coupling_set.hh), for the solvers that take them implicitly. `s`'s
/// applied, applied_stiffness, applied_damping and applied_group are sized (and cleared) by
/// the caller.
template <int dim>
void apply_to_body(const Footprint& fp, const Vec<dim>& force_on_body, double k, double b, int group, State<dim>& s) {
  apply_force_to_body<dim>(fp, force_on_body, s);
  k = tip_stiffness(k, fp);
  for (std::size_t p = 0; p < static_cast<std::size_t>(fp.count); ++p) {
    const int node = fp.node[p];
    const double w = fp.weight[p];
    if (node < s.applied_stiffness.size()) s.applied_stiffness[node] += w * k;
    if (node < s.applied_damping.size()) s.applied_damping[node] += w * b;
    if (node < s.applied_group.size()) s.applied_group[node] = group;
  }
}

} // namespace vtb
