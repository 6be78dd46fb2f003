#pragma once
/// \file
/// The virtual coupling between a device's handle and its proxy on the body, shared by the
/// haptics session's servo loop and the viewer's device mode.

#include "vtb/haptics/contact_result.hh"
#include "vtb/springs/spring_kernels.hh"

#include <array>

namespace vtb {

/// A spring k between handle and proxy, and a damper b on their relative velocity (the proxy
/// moves with the surface: the weighted velocities of the touched facet's nodes). Contact
/// pushes and never pulls: a negative normal part (the handle withdrawing faster than the
/// surface follows) is dropped, so the surface is not sticky. The force acts on the handle;
/// the body receives its negative at the facet's nodes, by the contact's weights.
template <int dim>
Vec<dim> virtual_coupling(const ContactResult<dim>& c, const std::array<int, dim>& facet, const Vec<dim>& handle,
                          const Vec<dim>& handle_velocity, const Nodal<dim>& node_velocity, double k, double b) {
  Vec<dim> proxy_velocity = Vec<dim>::Zero();
  for (std::size_t n = 0; n < static_cast<std::size_t>(dim); ++n)
    proxy_velocity += c.weights[n] * node_velocity.col(facet[n]);
  const Vec<dim> depth = c.proxy - handle;
  Vec<dim> f = k * depth + b * (proxy_velocity - handle_velocity);
  const double d2 = depth.squaredNorm();
  if (d2 > 0) {
    const double normal = f.dot(depth) / d2;
    if (normal < 0) f -= normal * depth;
  }
  return f;
}

} // namespace vtb
