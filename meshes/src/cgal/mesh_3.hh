#pragma once
// Mesh_3's pipeline shared by the solids (cgal_solid.cc) and a user's surface (cgal_surface.cc):
// the criteria (with a graded size field), the copy into a Mesh3, boundary groups, and the
// node-count rule. Internal to vtb_mesh_generators.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/quality.hh"

#include <Eigen/LU>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace vtb::mesh_3 {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polyhedron = CGAL::Surface_mesh<K::Point_3>;
namespace params = CGAL::parameters;

/// Copies the cells of a complex into a Mesh3, numbering vertices in geometric order. A cell
/// of zero volume (four coplanar vertices, which Mesh_3 can leave on a flat face beside a
/// protected sharp edge where a refinement meets it) is dropped: it holds no material.
/// `node_of`, when given, receives each kept vertex's node number.
template <typename C3t3>
Mesh3 to_mesh(const C3t3& c3t3, std::map<typename C3t3::Triangulation::Vertex_handle, int>* node_of = nullptr) {
  using Vh = typename C3t3::Triangulation::Vertex_handle;
  auto p = [](const Vh& v) {
    const auto& w = v->point();
    return Eigen::Vector3d(CGAL::to_double(w.x()), CGAL::to_double(w.y()), CGAL::to_double(w.z()));
  };
  std::vector<std::array<Vh, 4>> cells;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    const std::array<Vh, 4> h{c->vertex(0), c->vertex(1), c->vertex(2), c->vertex(3)};
    Eigen::Matrix3d e;
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
      e.col(k) = p(h[static_cast<std::size_t>(k + 1)]) - p(h[0]);
      longest = std::max(longest, e.col(k).norm());
    }
    if (std::abs(e.determinant()) > 1e-9 * longest * longest * longest) cells.push_back(h);
  }
  std::map<Vh, int> id;
  std::vector<Vh> verts;
  for (const auto& c : cells)
    for (const Vh& v : c)
      if (id.emplace(v, 0).second) verts.push_back(v);
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
  for (const auto& c : cells) m.cells.push_back({id[c[0]], id[c[1]], id[c[2]], id[c[3]]});
  check_and_orient(m);
  std::sort(m.cells.begin(), m.cells.end());
  if (node_of != nullptr) *node_of = std::move(id);
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

/// The element size of Mesh_3's criteria as a field: the body's size graded toward the
/// refinements (Mesh_3's MeshDomainField_3 signature).
struct SizeField {
  double body;
  const std::vector<Refinement>* refine;
  template <class P, class I> double operator()(const P& p, int, const I&) const {
    return graded_size(Eigen::Vector3d(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())), body,
                       *refine);
  }
};

/// The radius-edge bound of every generated tetrahedral mesh (circumradius / shortest edge).
inline constexpr double kRadiusEdge = 2.0;

/// Mesh_3 with the slab's criteria (docs/meshes.md). Mesh_3 refines until every cell meets
/// the radius-edge bound, but the perturbation and exudation that follow move vertices and
/// weights and can leave a cell above it (a held-out dome: 2.017). A mesh above kRadiusEdge is
/// remade with the criterion tightened by 10 % at a time, at most 3 times, and the best kept:
/// a mesh within the bound is the first try's, unchanged.
template <typename Domain, typename Tr, typename C3t3>
C3t3 run_mesh_3(const Domain& domain, double size, const std::vector<Refinement>& refine) {
  using Criteria = CGAL::Mesh_criteria_3<Tr>;
  const SizeField field{size, &refine};
  auto make = [&](double ratio) {
    const Criteria criteria = refine.empty()
                                  ? Criteria(params::edge_size = size, params::facet_angle = 25.0,
                                             params::facet_size = size, params::facet_distance = size / 10,
                                             params::cell_radius_edge_ratio = ratio, params::cell_size = size)
                                  : Criteria(params::edge_size = field, params::facet_angle = 25.0,
                                             params::facet_size = field, params::facet_distance = size / 10,
                                             params::cell_radius_edge_ratio = ratio, params::cell_size = field);
    // No time limits: the result must not depend on the machine's speed. Unset, CGAL bounds the
    // perturbation and the exudation by the time the refinement took, which cut the graded
    // bean's perturbation at a different point on each run; 0 is no limit.
    return CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_lloyd(), params::no_odt(),
                                   params::perturb(params::time_limit = 0, params::sliver_bound = 10.0),
                                   params::exude(params::time_limit = 0, params::sliver_bound = 10.0));
  };
  C3t3 best = make(kRadiusEdge);
  double worst = mesh_quality(to_mesh(best)).max_radius_edge;
  for (int retry = 1; retry <= 3 && worst > kRadiusEdge; ++retry) {
    C3t3 c = make(kRadiusEdge * std::pow(0.9, retry));
    const double w = mesh_quality(to_mesh(c)).max_radius_edge;
    if (w < worst) best = std::move(c), worst = w;
  }
  return best;
}

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

} // namespace vtb::mesh_3
