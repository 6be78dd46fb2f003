#pragma once
/// \file
/// The handle's proxy (god-object) against the deformed boundary of a 2D body: outside the
/// body the proxy is the handle; inside, it is held on the boundary, found by walking along
/// the boundary from where contact began, so a probe pressed deep never pops through to the
/// far side. Allocation-free after construction.

#include "vtb/haptics/contact_result.hh"
#include "vtb/meshes/mesh.hh"
#include "vtb/springs/spring_kernels.hh"

namespace vtb {

class BoundaryContact {
public:
  /// The boundary loops of the mesh (outward-oriented facets chained into a cycle).
  explicit BoundaryContact(const Mesh2& mesh);

  using Result = ContactResult<2>;

  /// Updates the proxy for the handle at `handle` with the body's nodes at `x` (deformed).
  /// `hold`: stay in contact though the handle is outside (a tip's face still above it).
  Result update(const Eigen::Vector2d& handle, const Nodal<2>& x, bool hold = false);
  void reset() { m_last = Result{}; }

  /// The boundary edges (Result::facet indexes them), outward oriented.
  const std::vector<std::array<int, 2>>& facets() const { return m_edges; }

private:
  bool inside(const Eigen::Vector2d& p, const Nodal<2>& x) const;
  /// Closest point on edge e to p; returns distance^2 and sets along.
  double closest_on(int e, const Eigen::Vector2d& p, const Nodal<2>& x, double& along) const;

  std::vector<std::array<int, 2>> m_edges; ///< boundary edges, in loop order
  std::vector<int> m_next, m_prev;         ///< neighbours along the loop
  Result m_last;
};

} // namespace vtb
