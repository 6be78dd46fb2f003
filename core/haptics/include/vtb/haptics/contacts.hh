#pragma once
/// \file
/// The probes' proxies against a body, one interface in 2D and 3D: the boundary walk per probe
/// (contact2d.hh), or one AABB tree over the surface and a proxy per probe (contact3d.hh).
/// `refit` moves the 3D tree to a new shape (nothing in 2D). Shared by `vtb haptics`'s servo
/// and the viewer's device mode.

#include "vtb/haptics/contact2d.hh"
#include "vtb/haptics/contact3d.hh"

#include <vector>

namespace vtb {

template <int dim> class Contacts;

template <> class Contacts<2> {
public:
  Contacts(const Mesh2& mesh, std::size_t probes) {
    m_c.reserve(probes);
    for (std::size_t i = 0; i < probes; ++i) m_c.emplace_back(mesh);
  }
  void refit(const Nodal<2>&) {}
  ContactResult<2> update(std::size_t i, const Eigen::Vector2d& h, const Nodal<2>& x) { return m_c[i].update(h, x); }
  const std::vector<std::array<int, 2>>& facets() const { return m_c.front().facets(); }

private:
  std::vector<BoundaryContact> m_c;
};

template <> class Contacts<3> {
public:
  Contacts(const Mesh3& mesh, std::size_t probes) : m_tree(mesh), m_c(probes, SurfaceContact(m_tree)) {}
  void refit(const Nodal<3>& x) { m_tree.rebuild(x); }
  ContactResult<3> update(std::size_t i, const Eigen::Vector3d& h, const Nodal<3>& x) { return m_c[i].update(h, x); }
  const std::vector<std::array<int, 3>>& facets() const { return m_tree.facets(); }

private:
  SurfaceTree m_tree;
  std::vector<SurfaceContact> m_c;
};

} // namespace vtb
