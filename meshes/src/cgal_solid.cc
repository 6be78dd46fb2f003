// 3D tetrahedral solids with CGAL Mesh_3: a slab with protected sharp edges and a sphere.
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/input_error.hh"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace vtb {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<K::Point_3>;
namespace params = CGAL::parameters;

/// A closed triangulated box surface with outward normals.
Surface box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Surface s;
  std::array<Surface::Vertex_index, 8> v;
  for (int c = 0; c < 8; ++c)
    v[static_cast<std::size_t>(c)] =
        s.add_vertex(K::Point_3(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z()));
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  auto pt = [&](int c) {
    const auto& p = s.point(v[static_cast<std::size_t>(c)]);
    return Eigen::Vector3d(p.x(), p.y(), p.z());
  };
  auto tri = [&](int a, int b, int c) {
    const Eigen::Vector3d n = (pt(b) - pt(a)).cross(pt(c) - pt(a));
    if (n.dot(pt(a) - centre) > 0)
      s.add_face(v[static_cast<std::size_t>(a)], v[static_cast<std::size_t>(b)], v[static_cast<std::size_t>(c)]);
    else
      s.add_face(v[static_cast<std::size_t>(a)], v[static_cast<std::size_t>(c)], v[static_cast<std::size_t>(b)]);
  };
  // Each face of the cube: corners with one coordinate bit fixed, split along a diagonal.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      std::array<int, 4> q{};
      int n = 0;
      for (int c = 0; c < 8; ++c)
        if (((c >> axis) & 1) == side) q[static_cast<std::size_t>(n++)] = c;
      // q holds the corners in binary order: (0, 1, 3, 2) walks around the face.
      tri(q[0], q[1], q[3]);
      tri(q[0], q[3], q[2]);
    }
  return s;
}

/// Copies the cells of a complex into a Mesh3, numbering vertices in geometric order.
template <typename C3t3> Mesh3 to_mesh(const C3t3& c3t3) {
  using Vh = typename C3t3::Triangulation::Vertex_handle;
  std::map<Vh, int> id;
  std::vector<Vh> verts;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c)
    for (int i = 0; i < 4; ++i)
      if (id.emplace(c->vertex(i), 0).second) verts.push_back(c->vertex(i));
  auto p = [](const Vh& v) {
    const auto& w = v->point();
    return Eigen::Vector3d(CGAL::to_double(w.x()), CGAL::to_double(w.y()), CGAL::to_double(w.z()));
  };
  std::sort(verts.begin(), verts.end(), [&](const Vh& a, const Vh& b) {
    const Eigen::Vector3d pa = p(a), pb = p(b);
    return std::lexicographical_compare(pa.data(), pa.data() + 3, pb.data(), pb.data() + 3);
  });
  Mesh3 m;
  m.points.resize(3, static_cast<Eigen::Index>(verts.size()));
  for (std::size_t i = 0; i < verts.size(); ++i) {
    id[verts[i]] = static_cast<int>(i);
    m.points.col(static_cast<Eigen::Index>(i)) = p(verts[i]);
  }
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c)
    m.cells.push_back({id[c->vertex(0)], id[c->vertex(1)], id[c->vertex(2)], id[c->vertex(3)]});
  check_and_orient(m);
  std::sort(m.cells.begin(), m.cells.end());
  return m;
}

/// Groups of boundary facets selected by a predicate on the facet's vertices.
template <typename Pred> void add_group(Mesh3& m, const std::string& name, Pred on) {
  MeshGroup<3> g;
  for (const auto& f : boundary_facets(m))
    if (on(m.points.col(f[0])) && on(m.points.col(f[1])) && on(m.points.col(f[2]))) {
      g.facets.push_back(f);
      g.nodes.insert(g.nodes.end(), f.begin(), f.end());
    }
  std::sort(g.nodes.begin(), g.nodes.end());
  g.nodes.erase(std::unique(g.nodes.begin(), g.nodes.end()), g.nodes.end());
  m.groups[name] = std::move(g);
}

template <typename Domain, typename Tr, typename C3t3>
C3t3 run_mesh_3(const Domain& domain, double size, double feature_size) {
  using Criteria = CGAL::Mesh_criteria_3<Tr>;
  const Criteria criteria(params::edge_size = feature_size, params::facet_angle = 25.0, params::facet_size = size,
                          params::facet_distance = size / 10, params::cell_radius_edge_ratio = 2.0,
                          params::cell_size = size);
  // No time limits anywhere: the result must be reproducible.
  return CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_lloyd(), params::no_odt(),
                                 params::perturb(params::sliver_bound = 10.0),
                                 params::exude(params::sliver_bound = 10.0));
}

Mesh3 mesh_slab(double size, const Eigen::Vector3d& hi = Eigen::Vector3d(0.2, 0.05, 0.02)) {
  using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K, Surface>;
  using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
  using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
  const Eigen::Vector3d lo(0, 0, 0);
  const Surface s = box_surface(lo, hi);
  Domain domain(s);
  domain.detect_features();
  Mesh3 m = to_mesh(run_mesh_3<Domain, Tr, C3t3>(domain, size, size));
  const double tol = 1e-9;
  const char* names[3][2] = {{"left", "right"}, {"bottom", "top"}, {"front", "back"}};
  for (int a = 0; a < 3; ++a) {
    add_group(m, names[a][0], [&](const Eigen::Vector3d& p) { return std::abs(p[a] - lo[a]) < tol; });
    add_group(m, names[a][1], [&](const Eigen::Vector3d& p) { return std::abs(p[a] - hi[a]) < tol; });
  }
  return m;
}

Mesh3 mesh_sphere(double size) {
  using Domain = CGAL::Labeled_mesh_domain_3<K>;
  using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
  using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
  const double R = 0.05;
  auto f = [R](const K::Point_3& p) { return (p.x() * p.x() + p.y() * p.y() + p.z() * p.z()) / (R * R) - 1.0; };
  const Domain domain = Domain::create_implicit_mesh_domain(f, K::Sphere_3(CGAL::ORIGIN, 1.21 * R * R),
                                                            params::relative_error_bound = 1e-8);
  Mesh3 m = to_mesh(run_mesh_3<Domain, Tr, C3t3>(domain, size, size));
  add_group(m, "surface", [](const Eigen::Vector3d&) { return true; });
  return m;
}

} // namespace

namespace {

/// Mesh_3 to about `nodes` nodes: a first guess of the element size from regular tetrahedra,
/// then the count's s^-3 law to correct it; the closest of at most 8 tries, within 15 %.
template <class Make> Mesh3 mesh_to_count(const std::string& what, double volume, int nodes, Make&& make) {
  if (nodes < 50 || nodes > 500'000)
    throw InputError(what + ": node count " + std::to_string(nodes) + " out of [50, 500000]");
  double size = std::cbrt(volume * std::sqrt(2.0) / nodes) * 1.6;
  Mesh3 best;
  for (int it = 0; it < 8; ++it) {
    Mesh3 m = make(size);
    const double ratio = static_cast<double>(m.num_nodes()) / nodes;
    if (best.num_nodes() == 0 || std::abs(m.num_nodes() - nodes) < std::abs(best.num_nodes() - nodes))
      best = std::move(m);
    if (std::abs(ratio - 1.0) <= 0.10) break;
    size *= std::cbrt(ratio);
  }
  if (std::abs(static_cast<double>(best.num_nodes()) / nodes - 1.0) > 0.15)
    throw InputError(what + ": could not reach about " + std::to_string(nodes) + " nodes (got " +
                     std::to_string(best.num_nodes()) + ")");
  best.source = "CGAL " + what + " (" + std::to_string(best.num_nodes()) + " nodes)";
  return best;
}

} // namespace

Mesh3 mesh_box(const Eigen::Vector3d& size, int nodes) {
  if (!(size.array() > 0).all()) throw InputError("box: the size must be > 0");
  return mesh_to_count("box", size.prod(), nodes, [&](double h) { return mesh_slab(h, size); });
}

Mesh3 mesh_solid(const std::string& shape, int nodes) {
  if (shape != "slab" && shape != "sphere") throw InputError("mesh_solid: shape must be slab or sphere, not " + shape);
  const double volume = shape == "slab" ? 0.2 * 0.05 * 0.02 : 4.0 / 3.0 * 3.14159265358979 * 0.05 * 0.05 * 0.05;
  return mesh_to_count(shape, volume, nodes, [&](double h) { return shape == "slab" ? mesh_slab(h) : mesh_sphere(h); });
}

} // namespace vtb
