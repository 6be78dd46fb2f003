#include "vtb/haptics/contact3d.hh"
#include "vtb/haptics/facet_rings.hh"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <atomic>

namespace vtb {
namespace {

/// Plain double arithmetic: a haptic query must not allocate, and an exact-predicate kernel
/// falls back to GMP numbers (which allocate) whenever the handle sits on a face. The queries
/// tolerate rounding: inside() votes over three rays, the walk compares distances.
using K = CGAL::Simple_cartesian<double>;

/// What the tree's primitives read their triangles from: the shared data of the tree.
struct Geometry {
  const std::vector<std::array<int, 3>>* triangles = nullptr;
  Nodal<3> x;
};

K::Point_3 point(const Nodal<3>& x, int node) {
  return {x(0, node), x(1, node), x(2, node)};
}
K::Point_3 point(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}

/// A surface triangle by index; its coordinates come from the tree's Geometry, so refitting
/// the tree to a new shape only needs the positions replaced and build() called.
struct TrianglePrimitive {
  using Id = int;
  using Datum = K::Triangle_3;
  using Point = K::Point_3;
  using Shared_data = const Geometry*;

  TrianglePrimitive() = default;
  TrianglePrimitive(std::vector<int>::const_iterator it, const Geometry*) : m_id(*it) {}
  Id id() const { return m_id; }
  Datum datum(Shared_data g) const {
    const auto& t = (*g->triangles)[static_cast<std::size_t>(m_id)];
    return {point(g->x, t[0]), point(g->x, t[1]), point(g->x, t[2])};
  }
  Point reference_point(Shared_data g) const { return point(g->x, (*g->triangles)[static_cast<std::size_t>(m_id)][0]); }
  static Shared_data construct_shared_data(const Geometry* g) { return g; }

  int m_id = 0;
};

using AabbTraits = CGAL::AABB_traits<K, TrianglePrimitive>;
using AabbTree = CGAL::AABB_tree<AabbTraits>;

/// The boxes of a fat tree: each node's box grown by `margin` on every side, so the tree stays
/// valid (conservative) while no node has moved more than `margin` since it was built: a
/// triangle whose vertices each moved less than m lies within m of where it was.
struct FatBbox {
  AabbTraits::Compute_bbox exact;
  double margin;
  template <typename It> CGAL::Bbox_3 operator()(It first, It beyond) const {
    const CGAL::Bbox_3 b = exact(first, beyond);
    return {b.xmin() - margin, b.ymin() - margin, b.zmin() - margin,
            b.xmax() + margin, b.ymax() + margin, b.zmax() + margin};
  }
};

} // namespace

/// One tree and the shape it reads: the servo queries one slot while the physics may build the
/// other (prepare), which the servo adopts at its next refit.
struct TreeSlot {
  Geometry geometry;
  Nodal<3> built; ///< the positions the boxes were built on
  AabbTree tree;
  /// CGAL's build with the fat boxes (custom_build: AABB_tree's build with its bbox functor swapped).
  void build(double margin) {
    tree.custom_build(FatBbox{tree.traits().compute_bbox_object(), margin}, tree.traits().split_primitives_object());
    built = geometry.x;
  }
};

struct SurfaceTree::Impl {
  std::array<TreeSlot, 2> slots;
  double margin = 0;
  std::atomic<int> in_use{0};                ///< the slot the servo queries (written by the servo)
  std::atomic<int> offered{0};               ///< the slot the physics last built (written by the physics)
  std::atomic<bool> physics_prepares{false}; ///< the physics offers every shape (real time): the servo only adopts
  TreeSlot& current() { return slots[static_cast<std::size_t>(in_use.load(std::memory_order_relaxed))]; }
  const TreeSlot& current() const { return slots[static_cast<std::size_t>(in_use.load(std::memory_order_relaxed))]; }
};

namespace {

double moved2(const Nodal<3>& x, const Nodal<3>& from) {
  return (x - from).colwise().squaredNorm().maxCoeff();
}

} // namespace

SurfaceTree::SurfaceTree(const Mesh3& mesh) : m_impl(std::make_unique<Impl>()) {
  m_triangles = boundary_facets(mesh);
  facet_rings(m_triangles, mesh.num_nodes(), m_ring_ptr, m_ring); // the triangles sharing a vertex
  // Margin: the mean surface edge length (a build or two per press of a few mm). Wider boxes
  // make each query slower (inside() 7 us at a quarter edge, 11 us at half an edge on the
  // 458-node slab); a build costs milliseconds on large bodies, so in real time the physics
  // builds the trees (prepare) and the servo only adopts them.
  double edges = 0;
  for (const auto& t : m_triangles)
    for (int k = 0; k < 3; ++k)
      edges +=
          (mesh.points.col(t[static_cast<std::size_t>(k)]) - mesh.points.col(t[static_cast<std::size_t>((k + 1) % 3)]))
              .norm();
  m_impl->margin = m_triangles.empty() ? 0.0 : 1.0 * edges / (3.0 * static_cast<double>(m_triangles.size()));
  std::vector<int> ids(m_triangles.size());
  for (std::size_t f = 0; f < ids.size(); ++f) ids[f] = static_cast<int>(f);
  for (TreeSlot& slot : m_impl->slots) {
    slot.geometry.triangles = &m_triangles;
    slot.geometry.x = mesh.points;
    slot.tree.insert(ids.cbegin(), ids.cend(), &slot.geometry);
    // Distance queries without CGAL's KD-tree hint: building that would allocate in the servo.
    slot.tree.do_not_accelerate_distance_queries();
    slot.build(m_impl->margin);
  }
}

SurfaceTree::~SurfaceTree() = default;

void SurfaceTree::rebuild(const Nodal<3>& x) {
  // A non-finite shape would break the ordering the build sorts by.
  if (x.cols() != m_impl->slots[0].geometry.x.cols() || !x.allFinite()) return;
  const int offered = m_impl->offered.load(std::memory_order_acquire);
  if (offered != m_impl->in_use.load(std::memory_order_relaxed)) {
    m_impl->in_use.store(offered, std::memory_order_release); // the physics' tree from here on
    ++m_adopted;
  }
  // Where the physics prepares the trees (real time), it has put each published shape into the
  // slot it offered before publishing it: the servo only swaps slots, whatever the body's size.
  if (m_impl->physics_prepares.load(std::memory_order_acquire)) return;
  TreeSlot& slot = m_impl->current();
  slot.geometry.x = x; // same size: no allocation; the triangles are read from here
  if (moved2(x, slot.built) > m_impl->margin * m_impl->margin) {
    slot.build(m_impl->margin); // reuses its node storage
    ++m_builds;
  }
}

void SurfaceTree::prepare(const Nodal<3>& x) {
  if (x.cols() != m_impl->slots[0].geometry.x.cols() || !x.allFinite()) return;
  m_impl->physics_prepares.store(true, std::memory_order_release);
  const int in_use = m_impl->in_use.load(std::memory_order_acquire);
  // The last offer not yet adopted: the servo may adopt it at any moment, so it is not touched
  // (the servo then reads the shape of the publish before this one).
  if (m_impl->offered.load(std::memory_order_relaxed) != in_use) return;
  const int spare = 1 - in_use;
  TreeSlot& slot = m_impl->slots[static_cast<std::size_t>(spare)];
  slot.geometry.x = x;
  // Its boxes, built on slot.built, stay conservative within the margin; built again past half
  // of it, so that a tree is never offered near its limit.
  if (moved2(x, slot.built) > 0.25 * m_impl->margin * m_impl->margin) {
    slot.build(m_impl->margin);
    m_prepared.fetch_add(1, std::memory_order_relaxed);
  }
  m_impl->offered.store(spare, std::memory_order_release);
}

double SurfaceTree::margin() const {
  return m_impl->margin;
}

bool SurfaceTree::inside(const Eigen::Vector3d& p) const {
  // Parity of the crossings of three rays in generic directions, majority vote: a ray through
  // an edge or a vertex (counted twice) can spoil one count, not two.
  static constexpr double dirs[3][3] = {{0.5773502691896258, 0.6123724356957945, 0.5400617248673217},
                                        {-0.7071067811865476, 0.3826834323650898, 0.5948227867513413},
                                        {0.2672612419124244, -0.8017837257372732, -0.5345224838248488}};
  if (!p.allFinite()) return false;
  int odd = 0;
  for (const auto& d : dirs) {
    const K::Ray_3 ray(point(p), K::Vector_3(d[0], d[1], d[2]));
    odd += static_cast<int>(m_impl->current().tree.number_of_intersected_primitives(ray) % 2);
  }
  return odd >= 2;
}

int SurfaceTree::crossing(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  if (!a.allFinite() || !b.allFinite() || a == b) return -1;
  const auto hit = m_impl->current().tree.any_intersected_primitive(K::Segment_3(point(a), point(b)));
  return hit ? *hit : -1;
}

int SurfaceTree::closest(const Eigen::Vector3d& p) const {
  return m_impl->current().tree.closest_point_and_primitive(point(p)).second;
}

double SurfaceTree::closest_on(int f, const Eigen::Vector3d& p, const Nodal<3>& x, Eigen::Vector3d& c,
                               std::array<double, 3>& w) const {
  const auto& t = m_triangles[static_cast<std::size_t>(f)];
  const K::Triangle_3 tri(point(x, t[0]), point(x, t[1]), point(x, t[2]));
  const K::Point_3 q = K().construct_projected_point_3_object()(tri, point(p));
  c = Eigen::Vector3d(q.x(), q.y(), q.z());
  // Barycentric weights of c = a + s (b - a) + u (d - a), from the 2x2 normal equations.
  const Eigen::Vector3d a = x.col(t[0]), e1 = x.col(t[1]) - a, e2 = x.col(t[2]) - a, r = c - a;
  const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), det = d11 * d22 - d12 * d12;
  double s = 0, u = 0;
  if (det > 0) {
    s = std::clamp((d22 * e1.dot(r) - d12 * e2.dot(r)) / det, 0.0, 1.0);
    u = std::clamp((d11 * e2.dot(r) - d12 * e1.dot(r)) / det, 0.0, 1.0 - s);
  }
  w = {1 - s - u, s, u};
  return (c - p).squaredNorm();
}

SurfaceContact::Result SurfaceContact::update(const Eigen::Vector3d& handle, const Nodal<3>& x, bool hold) {
  Result r;
  const Eigen::Vector3d previous = m_previous_handle;
  m_previous_handle = handle;
  if (!(hold && m_last.touching) && !m_tree->inside(handle)) {
    r.proxy = handle;
    m_last = r;
    return r;
  }
  int f = m_last.facet;
  if (!m_last.touching || f < 0) {
    // Contact begins where the handle's path since the last cycle crossed the surface; if it
    // did not (the body moved onto a resting handle), at the closest surface point.
    f = m_tree->crossing(previous, handle);
    if (f < 0) f = m_tree->closest(handle);
  }
  // Walk to the local minimum of the distance over triangles sharing a vertex: the proxy
  // stays on the side where contact began.
  Eigen::Vector3d c, cn;
  std::array<double, 3> w{}, wn{};
  double d = m_tree->closest_on(f, handle, x, c, w);
  for (std::size_t steps = 0; steps < facets().size(); ++steps) {
    int best = f;
    for (const int g : m_tree->ring(f)) {
      const double dg = m_tree->closest_on(g, handle, x, cn, wn);
      if (dg < d) best = g, d = dg, c = cn, w = wn;
    }
    if (best == f) break;
    f = best;
  }
  r.touching = true;
  r.facet = f;
  r.weights = w;
  r.proxy = c;
  m_last = r;
  return r;
}

void SurfaceContact::reset() {
  m_last = Result{};
  m_previous_handle.setConstant(std::numeric_limits<double>::quiet_NaN());
}

} // namespace vtb
