// 2D unstructured plates: CGAL constrained Delaunay refinement with an exact node count.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/quality.hh"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

namespace vtb {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Delaunay_mesh_vertex_base_2<K>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;

void insert_loop(CDT& cdt, const std::vector<Eigen::Vector2d>& loop) {
  const auto n = loop.size();
  std::vector<CDT::Vertex_handle> v;
  for (const auto& p : loop) v.push_back(cdt.insert(K::Point_2(p.x(), p.y())));
  for (std::size_t k = 0; k < n; ++k) cdt.insert_constraint(v[k], v[(k + 1) % n]);
}

/// The area enclosed by a simple closed loop (the shoelace formula).
double loop_area(const std::vector<Eigen::Vector2d>& loop) {
  double twice = 0;
  for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++)
    twice += loop[j].x() * loop[i].y() - loop[i].x() * loop[j].y();
  return std::abs(twice) / 2;
}

void insert_polygon(CDT& cdt, const Polygon& poly) {
  insert_loop(cdt, poly.vertices);
  for (const auto& h : poly.holes) insert_loop(cdt, h.vertices);
}

/// One point inside each hole (its vertex mean: the holes are convex).
std::vector<K::Point_2> hole_seeds(const Polygon& poly) {
  std::vector<K::Point_2> seeds;
  for (const auto& h : poly.holes) {
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (const auto& p : h.vertices) c += p / static_cast<double>(h.vertices.size());
    seeds.emplace_back(c.x(), c.y());
  }
  return seeds;
}

/// Sets in_domain to `value` on the faces reached from `start` without crossing a constraint
/// (each reached face is the first with another value, so every face is visited once).
void flood(CDT& cdt, CDT::Face_handle start, bool value) {
  std::vector<CDT::Face_handle> stack{start};
  start->set_in_domain(value);
  while (!stack.empty()) {
    const CDT::Face_handle f = stack.back();
    stack.pop_back();
    for (int i = 0; i < 3; ++i) {
      const CDT::Face_handle n = f->neighbor(i);
      if (n->is_in_domain() != value && !cdt.is_constrained(CDT::Edge(f, i))) {
        n->set_in_domain(value);
        stack.push_back(n);
      }
    }
  }
}

/// Marks the faces inside the constrained polygon and outside its holes: those that cannot be
/// reached from the infinite face, or from a point inside a hole, without crossing a
/// constraint. (A centroid test would misclassify the flat faces that round-off leaves between
/// the hull and points inserted on a slanted edge.)
void mark_domain(CDT& cdt, const Polygon& poly) {
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->set_in_domain(true);
  flood(cdt, cdt.infinite_face(), false);
  for (const auto& seed : hole_seeds(poly)) {
    const CDT::Face_handle f = cdt.locate(seed);
    if (f->is_in_domain()) flood(cdt, f, false);
  }
}

/// Refines with a size bound; returns the vertex count.
int refine(CDT& cdt, const Polygon& poly, double size) {
  cdt.clear();
  // No reserve(): CGAL orders handles by the time stamps of the Delaunay_mesh_*_base_2 types
  // (creation order, independent of the heap), but Compact_container::reserve in CGAL 5.5
  // leaves the reserved elements' time stamps uninitialised, so the order then depended on
  // whatever the heap held before (a test failed or passed with the build folder's path).
  insert_polygon(cdt, poly);
  Mesher mesher(cdt);
  const std::vector<K::Point_2> seeds = hole_seeds(poly); // the holes' faces are not refined
  mesher.set_seeds(seeds.begin(), seeds.end(), false);
  mesher.set_criteria(Criteria(0.125, size)); // B = sin^2(20.7 deg)
  mesher.refine_mesh();
  return static_cast<int>(cdt.number_of_vertices());
}

/// Adds `count` nodes at the centroids of the largest domain triangles (deterministic order).
void add_nodes(CDT& cdt, const Polygon& poly, int count) {
  for (int added = 0; added < count; ++added) {
    CDT::Face_handle best;
    double best_area = -1;
    K::Point_2 best_c;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (!f->is_in_domain()) continue;
      const double a = std::abs(cdt.triangle(f).area());
      const K::Point_2 c = CGAL::centroid(cdt.triangle(f));
      if (a > best_area * (1 + 1e-12) ||
          (a >= best_area * (1 - 1e-12) && (c.x() < best_c.x() || (c.x() == best_c.x() && c.y() < best_c.y())))) {
        best_area = a;
        best = f;
        best_c = c;
      }
    }
    cdt.insert(best_c);
    mark_domain(cdt, poly);
  }
}

Mesh2 to_mesh(const CDT& cdt, const Polygon& poly) {
  Mesh2 m;
  m.source = "CGAL plate";
  std::map<CDT::Vertex_handle, int> id;
  std::vector<Eigen::Vector2d> pts;
  // Number vertices in a geometric order (by x, then y) so that output is reproducible.
  std::vector<CDT::Vertex_handle> verts;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) verts.push_back(v);
  std::sort(verts.begin(), verts.end(), [](const auto& a, const auto& b) {
    return a->point().x() < b->point().x() || (a->point().x() == b->point().x() && a->point().y() < b->point().y());
  });
  m.points.resize(2, static_cast<Eigen::Index>(verts.size()));
  for (std::size_t i = 0; i < verts.size(); ++i) {
    id[verts[i]] = static_cast<int>(i);
    m.points.col(static_cast<Eigen::Index>(i)) << verts[i]->point().x(), verts[i]->point().y();
  }
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->is_in_domain()) m.cells.push_back({id[f->vertex(0)], id[f->vertex(1)], id[f->vertex(2)]});
  std::sort(m.cells.begin(), m.cells.end());
  check_and_orient(m);
  // Boundary groups: the boundary facets both of whose nodes lie on one of the group's edges
  // (edge k of `loop` runs from vertex k to k + 1).
  const double tol = 1e-9 * bounding_diagonal(m);
  const auto boundary = boundary_facets(m);
  auto group_on = [&](const std::vector<Eigen::Vector2d>& loop, const std::vector<int>& edges) {
    auto on_edge = [&](int node, int k) {
      const Eigen::Vector2d a = loop[static_cast<std::size_t>(k)];
      const Eigen::Vector2d d = loop[(static_cast<std::size_t>(k) + 1) % loop.size()] - a;
      const Eigen::Vector2d p = m.points.col(node);
      const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      return (a + t * d - p).norm() <= tol;
    };
    MeshGroup<2> g;
    for (const auto& f : boundary)
      for (int k : edges)
        if (on_edge(f[0], k) && on_edge(f[1], k)) {
          g.facets.push_back(f);
          g.nodes.insert(g.nodes.end(), f.begin(), f.end());
          break;
        }
    std::sort(g.nodes.begin(), g.nodes.end());
    g.nodes.erase(std::unique(g.nodes.begin(), g.nodes.end()), g.nodes.end());
    return g;
  };
  for (const auto& [name, edges] : poly.edge_groups) m.groups[name] = group_on(poly.vertices, edges);
  for (const auto& h : poly.holes) {
    std::vector<int> all(h.vertices.size());
    std::iota(all.begin(), all.end(), 0);
    m.groups[h.group] = group_on(h.vertices, all);
  }
  return m;
}

/// Smallest angle (degrees) of the triangles around node i, with i placed at p.
double min_angle_around(const Mesh2& m, const std::vector<int>& cells, int i, const Eigen::Vector2d& p) {
  double worst = 180;
  for (int c : cells) {
    const auto& t = m.cells[static_cast<std::size_t>(c)];
    Eigen::Vector2d x[3];
    for (int k = 0; k < 3; ++k)
      x[k] = t[static_cast<std::size_t>(k)] == i ? p : Eigen::Vector2d(m.points.col(t[static_cast<std::size_t>(k)]));
    const double area = 0.5 * ((x[1] - x[0]).x() * (x[2] - x[0]).y() - (x[1] - x[0]).y() * (x[2] - x[0]).x());
    if (area <= 0) return -1; // would invert
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d u = x[(k + 1) % 3] - x[k], v = x[(k + 2) % 3] - x[k];
      worst =
          std::min(worst, std::acos(std::clamp(u.dot(v) / (u.norm() * v.norm()), -1.0, 1.0)) * 180 / std::numbers::pi);
    }
  }
  return worst;
}

/// Smart Laplacian smoothing on fixed connectivity: each interior node moves to the mean of
/// its neighbours when that raises the smallest angle around it. Deterministic (node order),
/// unlike CGAL's Lloyd optimiser, which visits vertices in memory-address order and so
/// changes the last digits of the output from one build to the next.
void smooth(Mesh2& m, int sweeps) {
  const int n = m.num_nodes();
  std::vector<std::vector<int>> cells_of(static_cast<std::size_t>(n)), nbrs(static_cast<std::size_t>(n));
  for (std::size_t c = 0; c < m.cells.size(); ++c)
    for (int k = 0; k < 3; ++k) {
      const int i = m.cells[c][static_cast<std::size_t>(k)];
      cells_of[static_cast<std::size_t>(i)].push_back(static_cast<int>(c));
      for (int l = 0; l < 3; ++l)
        if (l != k) nbrs[static_cast<std::size_t>(i)].push_back(m.cells[c][static_cast<std::size_t>(l)]);
    }
  std::vector<char> fixed(static_cast<std::size_t>(n), 0);
  for (const auto& f : boundary_facets(m))
    for (int v : f) fixed[static_cast<std::size_t>(v)] = 1;
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (int i = 0; i < n; ++i) {
      if (fixed[static_cast<std::size_t>(i)]) continue;
      auto& nb = nbrs[static_cast<std::size_t>(i)];
      std::sort(nb.begin(), nb.end());
      nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (int j : nb) mean += m.points.col(j);
      mean /= static_cast<double>(nb.size());
      const auto& cs = cells_of[static_cast<std::size_t>(i)];
      if (min_angle_around(m, cs, i, mean) > min_angle_around(m, cs, i, m.points.col(i))) m.points.col(i) = mean;
    }
}

} // namespace

Polygon paper_plate() {
  Polygon p;
  p.vertices = {{0.0, 0.0}, {0.15, 0.0}, {0.2, 0.0125}, {0.2, 0.0375}, {0.15, 0.05}, {0.0, 0.05}};
  p.edge_groups = {{"clamp", {5}}, {"load", {2}}, {"free", {0, 1, 3, 4}}};
  return p;
}

Mesh2 mesh_rectangle(const Eigen::Vector2d& size, int nodes, double hole_radius) {
  if (!(size.array() > 0).all()) throw InputError("rectangle: the size must be > 0");
  Polygon p;
  p.vertices = {{0.0, 0.0}, {size.x(), 0.0}, {size.x(), size.y()}, {0.0, size.y()}};
  p.edge_groups = {{"bottom", {0}}, {"right", {1}}, {"top", {2}}, {"left", {3}}};
  if (hole_radius > 0) {
    if (const std::string why = hole_error(hole_radius, size.minCoeff()); !why.empty())
      throw InputError("rectangle: " + why);
    // Edges about as long as the mesh's (an equilateral mesh of `nodes` nodes over the area).
    const double area = size.prod() - std::numbers::pi * hole_radius * hole_radius;
    const double h = std::sqrt(2.0 * area / (std::sqrt(3.0) * nodes));
    const int sides = std::max(16, static_cast<int>(std::ceil(2 * std::numbers::pi * hole_radius / h)));
    Hole hole{{}, "hole"};
    for (int k = 0; k < sides; ++k) {
      const double a = 2 * std::numbers::pi * k / sides;
      hole.vertices.emplace_back(size.x() / 2 + hole_radius * std::cos(a), size.y() / 2 + hole_radius * std::sin(a));
    }
    p.holes.push_back(std::move(hole));
  }
  Mesh2 m = mesh_polygon(p, nodes);
  m.source = std::string(hole_radius > 0 ? "CGAL rectangle with a hole (" : "CGAL rectangle (") +
             std::to_string(m.num_nodes()) + " nodes)";
  return m;
}

Mesh2 mesh_polygon(const Polygon& poly, int nodes, double min_angle_deg) {
  if (poly.vertices.size() < 3) throw InputError("polygon: needs at least 3 vertices");
  if (nodes < static_cast<int>(poly.vertices.size()) || nodes > 2'000'000)
    throw InputError("polygon: node count " + std::to_string(nodes) + " out of range");
  double area = loop_area(poly.vertices);
  for (const auto& h : poly.holes) area -= loop_area(h.vertices);
  // Scan size bounds around the estimate h0 (equilateral cells of edge h have sqrt(3)/2 h^2
  // per node) and keep the candidates closest below the target.
  const double h0 = std::sqrt(2.0 * area / (std::sqrt(3.0) * nodes));
  CDT cdt;
  std::vector<std::pair<int, double>> candidates; // (missing nodes, size)
  for (int s = 0; s <= 400; ++s) {
    const double size = h0 * std::pow(4.0, s / 400.0) * 0.7;
    const int n = refine(cdt, poly, size);
    if (n <= nodes) candidates.push_back({nodes - n, size});
  }
  std::sort(candidates.begin(), candidates.end());
  for (const auto& [missing, size] : candidates) {
    if (missing > std::max(3, nodes / 20)) break; // too far: quality would suffer
    refine(cdt, poly, size);
    mark_domain(cdt, poly);
    add_nodes(cdt, poly, missing);
    mark_domain(cdt, poly);
    Mesh2 m = to_mesh(cdt, poly);
    smooth(m, 10);
    if (m.num_nodes() == nodes && mesh_quality(m).min_angle >= min_angle_deg) {
      m.source = "CGAL plate (" + std::to_string(nodes) + " nodes)";
      return m;
    }
  }
  throw InputError("polygon: no mesh with exactly " + std::to_string(nodes) +
                   " nodes and angles >= " + std::to_string(min_angle_deg) + " degrees was found");
}

} // namespace vtb
