#pragma once
/// \file
/// The probes' proxies against a body, one interface in 2D and 3D: the boundary walk per probe
/// (contact2d.hh), or one AABB tree over the surface and a proxy per probe (contact3d.hh).
/// `refit` moves the 3D tree to a new shape (nothing in 2D). Each proxy then takes the tool
/// tip's footprint (footprint.hh; a radius of 0: the point proxy's facet). Shared by `vtb
/// haptics`'s servo and the viewer's device mode.

#include "vtb/haptics/contact2d.hh"
#include "vtb/haptics/contact3d.hh"
#include "vtb/haptics/footprint.hh"
#include "vtb/problem/scene.hh"

#include <vector>

namespace vtb {

template <int dim> class Contacts;

/// One probe's cycle: the point contact, then the tip's footprint. A tip spreads its force, so
/// the surface under its centre can sink below the handle while the tip's face (the
/// footprint's mean) is still above it: contact holds while the last face is above the handle,
/// and ends when the new one is not.
template <int dim, class PointContact>
ContactResult<dim> hold_tip(PointContact& point, ContactResult<dim>& last, TipFootprint<dim>& tip,
                            const Eigen::Matrix<double, dim, 1>& h, const Nodal<dim>& x) {
  const bool hold = tip.radius() > 0 && last.touching && last.normal.dot(last.proxy - h) > 0;
  ContactResult<dim> c = point.update(h, x, hold);
  tip.place(c, h, x);
  if (c.touching && hold && !(c.normal.dot(c.proxy - h) > 0)) {
    point.reset();
    c = ContactResult<dim>{};
    c.proxy = h;
  }
  last = c;
  return c;
}

template <> class Contacts<2> {
public:
  Contacts(const Mesh2& mesh, std::size_t probes, double tip_radius = 0.0, const MaterialDesc& material = {})
      : m_c(probes, BoundaryContact(mesh)), m_tip(m_c.front().facets(), mesh.points, tip_radius, material.young_modulus,
                                                  material.poisson_ratio, material.thickness) {}
  void refit(const Nodal<2>&) {}
  void prepare(const Nodal<2>&) {}
  ContactResult<2> update(std::size_t i, const Eigen::Vector2d& h, const Nodal<2>& x) {
    return hold_tip(m_c[i], m_last[i], m_tip, h, x);
  }
  const std::vector<std::array<int, 2>>& facets() const { return m_c.front().facets(); }
  const TipFootprint<2>& tip() const { return m_tip; }

private:
  std::vector<BoundaryContact> m_c;
  TipFootprint<2> m_tip;
  std::vector<ContactResult<2>> m_last = std::vector<ContactResult<2>>(m_c.size());
};

template <> class Contacts<3> {
public:
  Contacts(const Mesh3& mesh, std::size_t probes, double tip_radius = 0.0, const MaterialDesc& material = {})
      : m_tree(mesh), m_c(probes, SurfaceContact(m_tree)),
        m_tip(m_tree.facets(), mesh.points, tip_radius, material.young_modulus, material.poisson_ratio) {}
  void refit(const Nodal<3>& x) { m_tree.rebuild(x); }
  /// From the physics' thread: the next contact tree built there (SurfaceTree::prepare).
  void prepare(const Nodal<3>& x) { m_tree.prepare(x); }
  const SurfaceTree& tree() const { return m_tree; }
  ContactResult<3> update(std::size_t i, const Eigen::Vector3d& h, const Nodal<3>& x) {
    return hold_tip(m_c[i], m_last[i], m_tip, h, x);
  }
  const std::vector<std::array<int, 3>>& facets() const { return m_tree.facets(); }
  const TipFootprint<3>& tip() const { return m_tip; }

private:
  SurfaceTree m_tree;
  std::vector<SurfaceContact> m_c;
  TipFootprint<3> m_tip;
  std::vector<ContactResult<3>> m_last = std::vector<ContactResult<3>>(m_c.size());
};

} // namespace vtb
