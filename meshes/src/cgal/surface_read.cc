// Reading and checking a user's closed surface (surface.hh): pre-scan, CGAL's readers, checks.
#include "vtb/meshes/surface.hh"

#include "vtb/base/input_error.hh"
#include "vtb/meshes/isolated.hh"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <map>
#include <sstream>

namespace vtb {
namespace {

// Exact predicates: the self-intersection test decides with the kernel's predicates, and with
// floating-point ones (Simple_cartesian) it took two coplanar triangles of a cylinder's side,
// stacked and sharing one vertex, for crossing. Constructions stay inexact.
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Polygons = std::vector<std::vector<std::size_t>>;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

std::string where(const Point& p) {
  std::ostringstream os;
  os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return os.str();
}

/// The whitespace-separated tokens of the text up to `limit` bytes, skipping '#' comments.
std::vector<std::string_view> header_tokens(std::string_view s, std::size_t count) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size() && out.size() < count) {
    const char c = s[i];
    if (c == '#') {
      while (i < s.size() && s[i] != '\n') ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else {
      const std::size_t b = i;
      while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i])) && s[i] != '#') ++i;
      out.push_back(s.substr(b, i - b));
    }
  }
  return out;
}

unsigned long long as_count(std::string_view t, const std::string& src, const char* what) {
  unsigned long long v = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || ptr != t.data() + t.size()) throw InputError(src + ": " + what + " is not a count");
  return v;
}

void check_fits(unsigned long long need, std::size_t size, const std::string& src, const std::string& what) {
  if (need > size)
    throw InputError(src + ": " + what + " need at least " + std::to_string(need) + " bytes; the file has " +
                     std::to_string(size));
}

void prescan_off(std::string_view s, const std::string& src) {
  const auto t = header_tokens(s, 4);
  if (t.empty() || t[0].find("OFF") == std::string_view::npos)
    throw InputError(src + ": not an OFF file (no OFF header)");
  if (t.size() < 3) throw InputError(src + ": OFF header without vertex and face counts");
  if (t[1] == "BINARY") throw InputError(src + ": binary OFF is not read (ASCII OFF, STL, OBJ or PLY)");
  const unsigned long long nv = as_count(t[1], src, "the OFF vertex count");
  const unsigned long long nf = as_count(t[2], src, "the OFF face count");
  if (nv > (1ull << 32) || nf > (1ull << 32)) throw InputError(src + ": OFF counts beyond 2^32");
  // A vertex is at least "0 0 0\n", a face "3 0 1 2\n".
  check_fits(nv * 6 + nf * 8, s.size(), src,
             "the declared " + std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces");
}

void prescan_ply(std::string_view s, const std::string& src) {
  const std::size_t end = s.find("end_header");
  if (s.substr(0, 3) != "ply" || end == std::string_view::npos)
    throw InputError(src + ": not a PLY file (no ply ... end_header)");
  const bool ascii = s.substr(0, end).find("format ascii") != std::string_view::npos;
  // CGAL's PLY reader takes a property before any element as the last element's (of none).
  if (const std::size_t prop = s.find("property"), elem = s.find("element ");
      prop < end && (elem == std::string_view::npos || prop < elem))
    throw InputError(src + ": PLY header has a property before any element");
  std::size_t pos = 0;
  unsigned long long need = 0;
  while ((pos = s.find("element ", pos)) != std::string_view::npos && pos < end) {
    pos += 8;
    const auto t = header_tokens(s.substr(pos, std::min<std::size_t>(end - pos, 200)), 2);
    if (t.size() < 2) throw InputError(src + ": PLY element without a count");
    const unsigned long long n = as_count(t[1], src, "a PLY element count");
    if (n > (1ull << 32)) throw InputError(src + ": PLY element count beyond 2^32");
    need += n * (t[0] == "vertex" ? (ascii ? 6 : 12) : t[0] == "face" ? (ascii ? 8 : 13) : 1);
  }
  check_fits(need, s.size(), src, "the declared PLY elements");
}

void prescan_stl(std::string_view s, const std::string& src) {
  std::size_t b = 0;
  while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  const bool ascii = s.substr(b, 5) == "solid" && s.find("facet") != std::string_view::npos;
  if (ascii) return;
  if (s.size() < 84) throw InputError(src + ": binary STL shorter than its 84-byte header");
  std::uint32_t n = 0;
  std::memcpy(&n, s.data() + 80, 4);
  const unsigned long long need = 84 + 50ull * n;
  if (need != s.size())
    throw InputError(src + ": binary STL declares " + std::to_string(n) + " triangles (" + std::to_string(need) +
                     " bytes); the file has " + std::to_string(s.size()) + (need > s.size() ? " (truncated)" : ""));
}

bool read_soup(std::string_view content, std::string_view format, std::vector<Point>& points, Polygons& polygons) {
  std::istringstream in(std::string(content), std::ios::in | std::ios::binary);
  const auto quiet = CGAL::parameters::verbose(false);
  if (format == ".off") return CGAL::IO::read_OFF(in, points, polygons, quiet);
  if (format == ".obj") return CGAL::IO::read_OBJ(in, points, polygons, quiet);
  if (format == ".ply") return CGAL::IO::read_PLY(in, points, polygons, quiet);
  std::vector<std::array<std::size_t, 3>> tris;
  const bool ok = CGAL::IO::read_STL(in, points, tris, quiet);
  for (const auto& t : tris) polygons.push_back({t[0], t[1], t[2]});
  return ok;
}

/// Indices in range, finite coordinates, no repeated or collinear corner.
void check_faces(const std::vector<Point>& points, const Polygons& polygons, const std::string& src) {
  if (polygons.empty()) throw InputError(src + ": the surface has no faces");
  for (const Point& p : points)
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      throw InputError(src + ": a vertex coordinate is not finite");
  CGAL::Bbox_3 box;
  for (const Point& p : points) box += p.bbox();
  const double diag2 = CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                       CGAL::square(box.zmax() - box.zmin());
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const auto& poly = polygons[f];
    const std::string face = "face " + std::to_string(f);
    if (poly.size() < 3) throw InputError(src + ": " + face + " has fewer than 3 vertices");
    for (std::size_t v : poly)
      if (v >= points.size())
        throw InputError(src + ": " + face + " names vertex " + std::to_string(v) + " of " +
                         std::to_string(points.size()));
    std::vector<std::size_t> sorted = poly;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      throw InputError(src + ": degenerate " + face + " (a repeated vertex) at " + where(points[poly[0]]));
    // The polygon's area vector (Newell): zero for a collinear face.
    K::Vector_3 area(0, 0, 0);
    for (std::size_t i = 0; i < poly.size(); ++i)
      area = area +
             CGAL::cross_product(points[poly[i]] - CGAL::ORIGIN, points[poly[(i + 1) % poly.size()]] - CGAL::ORIGIN);
    if (area.squared_length() <= 1e-24 * diag2 * diag2)
      throw InputError(src + ": degenerate " + face + " (zero area) at " + where(points[poly[0]]));
  }
}

/// Every edge shared by exactly two faces: one face is an open boundary, three a non-manifold edge.
void check_closed_manifold(const std::vector<Point>& points, const Polygons& polygons, const std::string& src) {
  std::map<std::pair<std::size_t, std::size_t>, int> uses;
  for (const auto& poly : polygons)
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const std::size_t a = poly[i], b = poly[(i + 1) % poly.size()];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::size_t open = 0;
  const std::pair<std::size_t, std::size_t>* first_open = nullptr;
  for (const auto& [e, n] : uses) {
    if (n > 2)
      throw InputError(src + ": not manifold: the edge from " + where(points[e.first]) + " to " +
                       where(points[e.second]) + " is shared by " + std::to_string(n) + " faces");
    if (n == 1 && open++ == 0) first_open = &e;
  }
  if (open > 0)
    throw InputError(src + ": not closed: " + std::to_string(open) + " boundary edges, one from " +
                     where(points[first_open->first]) + " to " + where(points[first_open->second]));
}

std::string encode(const Surface& s) {
  std::string out;
  auto put = [&](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  const std::uint64_t np = s.points.size(), nt = s.triangles.size();
  put(&np, 8);
  put(&nt, 8);
  for (const auto& p : s.points) put(p.data(), 24);
  for (const auto& t : s.triangles) put(t.data(), 12);
  put(&s.reoriented, 4);
  return out;
}

Surface decode(std::string_view d, const std::string& src) {
  Surface s;
  std::uint64_t np = 0, nt = 0;
  if (d.size() < 16) throw InputError(src + ": the surface reader sent an incomplete surface");
  std::memcpy(&np, d.data(), 8);
  std::memcpy(&nt, d.data() + 8, 8);
  if (np > d.size() / 24 || nt > d.size() / 12 || d.size() != 16 + np * 24 + nt * 12 + 4)
    throw InputError(src + ": the surface reader sent an incomplete surface");
  s.points.resize(np);
  s.triangles.resize(nt);
  std::size_t at = 16;
  for (auto& p : s.points) std::memcpy(p.data(), d.data() + at, 24), at += 24;
  for (auto& t : s.triangles) {
    std::memcpy(t.data(), d.data() + at, 12), at += 12;
    for (int v : t)
      if (v < 0 || static_cast<std::uint64_t>(v) >= np) throw InputError(src + ": the surface reader sent a bad index");
  }
  std::memcpy(&s.reoriented, d.data() + at, 4);
  return s;
}

} // namespace

void prescan_surface(std::string_view content, std::string_view format, const std::string& src) {
  if (format == ".off") return prescan_off(content, src);
  if (format == ".ply") return prescan_ply(content, src);
  if (format == ".stl") return prescan_stl(content, src);
  if (format == ".obj") return;
  throw InputError(src + ": unknown surface format '" + std::string(format) + "' (.off, .stl, .obj or .ply)");
}

Surface parse_surface(std::string_view content, std::string_view format, const std::string& src, double scale) {
  if (content.empty()) throw InputError(src + ": the file is empty");
  prescan_surface(content, format, src);
  std::vector<Point> points;
  Polygons polygons;
  if (!read_soup(content, format, points, polygons))
    throw InputError(src + ": not a readable " + std::string(format.substr(1)) + " surface (CGAL's reader failed)");
  std::vector<Eigen::Vector3d> p;
  p.reserve(points.size());
  for (const Point& q : points) p.emplace_back(q.x(), q.y(), q.z());
  return checked_surface(std::move(p), std::move(polygons), src, scale);
}

Surface checked_surface(std::vector<Eigen::Vector3d> in_points, std::vector<std::vector<std::size_t>> polygons,
                        const std::string& src, double scale) {
  if (!(scale > 0) || !std::isfinite(scale)) throw InputError(src + ": the scale must be > 0");
  std::vector<Point> points;
  points.reserve(in_points.size());
  for (const auto& q : in_points) points.emplace_back(q.x(), q.y(), q.z());
  check_faces(points, polygons, src);
  PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
  check_faces(points, polygons, src); // merging may have made a face degenerate
  check_closed_manifold(points, polygons, src);
  const std::size_t before = points.size();
  Polygons oriented = polygons;
  if (!PMP::orient_polygon_soup(points, oriented) || points.size() != before)
    throw InputError(src + ": not manifold: the vertex at " + where(points[std::min(before, points.size() - 1)]) +
                     " joins sheets of the surface that touch only there");
  Surface s;
  for (std::size_t f = 0; f < polygons.size(); ++f) s.reoriented += oriented[f] != polygons[f];
  SurfaceMesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, oriented, mesh);
  // Polygons are split by CGAL's hole filling (triangulate_hole_polyline), not by its default
  // constrained Delaunay triangulation in the polygon's projection plane: the latter is undefined
  // behaviour (a null reference in CGAL 5.5's CDT) when the projection folds over itself. The
  // triangle copy-out below needs three corners a face: a polygon left unsplit is refused here,
  // by a corner of it (the soup's face numbers do not survive the conversion). What the split
  // leaves crossing is refused by the self-intersection test.
  if (!CGAL::is_triangle_mesh(mesh)) PMP::triangulate_faces(mesh, CGAL::parameters::use_delaunay_triangulation(false));
  for (auto f : mesh.faces())
    if (mesh.degree(f) != 3)
      throw InputError(src + ": a face of " + std::to_string(mesh.degree(f)) + " vertices near " +
                       where(mesh.point(mesh.target(mesh.halfedge(f)))) +
                       " cannot be split into triangles (it folds over itself or is far from planar)");
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> crossing;
  PMP::self_intersections(mesh, std::back_inserter(crossing), CGAL::parameters::maximum_number(1));
  if (!crossing.empty()) {
    const auto h = mesh.halfedge(crossing[0].first);
    throw InputError(src + ": self-intersecting: faces " + std::to_string(crossing[0].first.idx()) + " and " +
                     std::to_string(crossing[0].second.idx()) + " cross near " + where(mesh.point(mesh.target(h))));
  }
  if (!PMP::is_outward_oriented(mesh)) {
    PMP::reverse_face_orientations(mesh);
    s.reoriented = static_cast<int>(mesh.number_of_faces()) - s.reoriented;
  }
  std::map<SurfaceMesh::Vertex_index, int> id;
  for (auto v : mesh.vertices()) {
    id[v] = static_cast<int>(s.points.size());
    const Point& p = mesh.point(v);
    s.points.emplace_back(scale * p.x(), scale * p.y(), scale * p.z());
  }
  for (auto f : mesh.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) t[static_cast<std::size_t>(k++)] = id[v];
    s.triangles.push_back(t);
  }
  return s;
}

Surface read_surface(const std::filesystem::path& file, double scale) {
  const std::string src = file.string();
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (std::find(kSurfaceFormats.begin(), kSurfaceFormats.end(), ext) == kSurfaceFormats.end())
    throw InputError(src + ": unknown surface format '" + ext + "' (.off, .stl, .obj or .ply)");
  const std::string content = read_untrusted(file, "surface");
  const Surface s = decode(run_isolated(src, "surface", std::chrono::seconds(8),
                                        [&] { return encode(parse_surface(content, ext, src, scale)); }),
                           src);
  if (s.reoriented > 0)
    std::cerr << "vtb: warning: " << src << ": " << s.reoriented << " faces reoriented (outward, consistently)\n";
  return s;
}

} // namespace vtb
