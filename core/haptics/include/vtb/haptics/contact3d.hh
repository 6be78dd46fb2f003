#pragma once
/// \file
/// The handle's proxy (god-object) against the deformed surface of a 3D body.
///
/// `SurfaceTree` holds the body's boundary triangles, the triangles around each one and a CGAL
/// AABB tree over them with fat boxes: every box grown by a margin (a quarter of the mean surface edge).
/// The triangles are read from the latest shape; the boxes stay valid until some node has moved
/// more than the margin since they were built, and only then are they built again (CGAL's
/// build reuses its node storage: no allocation after construction). One tree serves every
/// probe; CGAL stays inside contact3d.cc.
///
/// `SurfaceContact` is one probe's proxy. Outside the body the proxy is the handle. Contact
/// begins where the handle's path since the last cycle crossed the surface (a segment query on
/// the tree); from then on the proxy is the local closest surface point, found by walking over
/// triangles that share a vertex with the current one while the distance falls, so a probe
/// pressed deep never pops through to the far side. Inside/outside is ray parity on the tree.

#include "vtb/haptics/contact_result.hh"
#include "vtb/meshes/mesh.hh"
#include "vtb/springs/spring_kernels.hh"

#include <atomic>
#include <limits>
#include <memory>
#include <span>

namespace vtb {

class SurfaceTree {
public:
  /// The boundary triangles of the mesh (outward oriented) and the tree at the rest shape.
  explicit SurfaceTree(const Mesh3& mesh);
  ~SurfaceTree();
  SurfaceTree(const SurfaceTree&) = delete;
  SurfaceTree& operator=(const SurfaceTree&) = delete;

  /// Servo side: adopts the slot the physics last offered, if any. Where the physics prepares
  /// (real time) that is all it does, in constant time: the offered slot holds the published
  /// shape. Otherwise (lockstep) it moves the tree to the body's nodes at `x`, building its boxes
  /// again when a node has moved more than margin() since the last build. A non-finite `x` is
  /// ignored (the watchdog deals with it), as a wrong node count would be.
  void rebuild(const Nodal<3>& x);
  /// Physics side (another thread than rebuild's and the queries'), before it publishes `x`:
  /// puts `x` into the spare slot, builds that slot's boxes again once a node has moved more than
  /// half the margin since they were built, and offers the slot to the servo; nothing while the
  /// last offer waits to be adopted. From its first call the servo builds and copies nothing.
  void prepare(const Nodal<3>& x);
  double margin() const;
  long builds() const { return m_builds; }   ///< builds in the servo (rebuild) since construction
  long adopted() const { return m_adopted; } ///< trees the servo took from the physics
  long prepared() const { return m_prepared.load(std::memory_order_relaxed); } ///< trees the physics built
  /// Whether p is inside the body as the tree last saw it (ray parity, majority of three rays).
  bool inside(const Eigen::Vector3d& p) const;
  /// A triangle crossed by the segment [a, b], or -1.
  int crossing(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  /// The triangle closest to p.
  int closest(const Eigen::Vector3d& p) const;
  /// Closest point c on triangle f (nodes at x) to p with its barycentric weights; returns |c - p|^2.
  double closest_on(int f, const Eigen::Vector3d& p, const Nodal<3>& x, Eigen::Vector3d& c,
                    std::array<double, 3>& w) const;

  /// The surface triangles, outward oriented.
  const std::vector<std::array<int, 3>>& facets() const { return m_triangles; }
  /// The triangles sharing a vertex with triangle f.
  std::span<const int> ring(int f) const {
    const auto b = static_cast<std::size_t>(m_ring_ptr[static_cast<std::size_t>(f)]);
    const auto e = static_cast<std::size_t>(m_ring_ptr[static_cast<std::size_t>(f) + 1]);
    return {m_ring.data() + b, e - b};
  }

private:
  struct Impl; ///< the CGAL tree and the positions it was built on
  std::vector<std::array<int, 3>> m_triangles;
  std::vector<int> m_ring_ptr, m_ring; ///< CSR
  std::unique_ptr<Impl> m_impl;
  long m_builds = 0;
  long m_adopted = 0;
  std::atomic<long> m_prepared{0};
};

class SurfaceContact {
public:
  using Result = ContactResult<3>;
  explicit SurfaceContact(const SurfaceTree& tree) : m_tree(&tree) {}

  /// Updates the proxy for the handle at `handle`, with the body's nodes at `x` (deformed,
  /// close to the tree's last rebuild). `hold`: stay in contact though the handle is outside
  /// (a tip's face still above it). Allocation-free.
  Result update(const Eigen::Vector3d& handle, const Nodal<3>& x, bool hold = false);
  void reset();
  const std::vector<std::array<int, 3>>& facets() const { return m_tree->facets(); }

private:
  const SurfaceTree* m_tree;
  Eigen::Vector3d m_previous_handle = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Result m_last;
};

} // namespace vtb
