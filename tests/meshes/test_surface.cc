// A user's closed surface: read in every format, checked, meshed by CGAL to a node count with the
// slab's quality bounds, graded toward a point; bad surfaces refused with one line.
#include "support/fresh_dir.hh"
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/quality.hh"
#include "vtb/meshes/surface.hh"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <thread>

namespace vtb {
namespace {

using Tri = std::array<int, 3>;

/// A torus (R 30 mm, r 12 mm) as n x m quads split in two: a shape with a hole, no sharp edge,
/// made here (not a file of the repository).
void torus(std::vector<Eigen::Vector3d>& v, std::vector<Tri>& f, int n = 48, int m = 24) {
  const double R = 0.03, r = 0.012, tau = 2 * std::numbers::pi;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double a = tau * i / n, b = tau * j / m;
      v.emplace_back((R + r * std::cos(b)) * std::cos(a), (R + r * std::cos(b)) * std::sin(a), r * std::sin(b));
    }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const int a = i * m + j, b = ((i + 1) % n) * m + j, c = ((i + 1) % n) * m + (j + 1) % m, d = i * m + (j + 1) % m;
      f.push_back({a, b, c});
      f.push_back({a, c, d});
    }
}

/// A cylinder (R 25 mm, H 30 mm) with n sides and its side in m rows of quads split in two; top
/// and bottom are fans. Each side strip is one exact plane, so a row's triangles and the next
/// row's lie in one plane and share a vertex: a valid surface that only exact predicates pass.
void cylinder(std::vector<Eigen::Vector3d>& v, std::vector<Tri>& f, int n = 72, int m = 12) {
  const double R = 0.025, H = 0.03, tau = 2 * std::numbers::pi;
  v = {{0, 0, 0}, {0, 0, H}};
  for (int k = 0; k <= m; ++k)
    for (int i = 0; i < n; ++i) v.emplace_back(R * std::cos(tau * i / n), R * std::sin(tau * i / n), H * k / m);
  const auto ring = [&](int k, int i) { return 2 + k * n + i % n; };
  for (int i = 0; i < n; ++i) {
    f.push_back({0, ring(0, i + 1), ring(0, i)});
    f.push_back({1, ring(m, i), ring(m, i + 1)});
    for (int k = 0; k < m; ++k) {
      f.push_back({ring(k, i), ring(k, i + 1), ring(k + 1, i + 1)});
      f.push_back({ring(k, i), ring(k + 1, i + 1), ring(k + 1, i)});
    }
  }
}

/// A dome: the unit icosphere subdivided `levels` times (midpoints pushed out to the sphere),
/// mapped onto the superellipsoid |x/a|^3 + |y/b|^3 + |z/c|^3 = 1 (60 x 44 x 32 mm) and cut flat
/// at z = -10 mm: a smooth top over a sharp rim, made here (not a file of the repository).
void dome(std::vector<Eigen::Vector3d>& v, std::vector<Tri>& f, int levels = 5) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p /= p.norm();
  f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto at = [&](int a, int b) {
      const auto [it, fresh] = mid.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<int>(v.size()));
      if (fresh) {
        const Eigen::Vector3d m = v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)];
        v.push_back(m / m.norm());
      }
      return it->second;
    };
    std::vector<Tri> finer;
    for (const auto& [a, b, c] : f) {
      const int ab = at(a, b), bc = at(b, c), ca = at(c, a);
      finer.insert(finer.end(), {Tri{a, ab, ca}, Tri{b, bc, ab}, Tri{c, ca, bc}, Tri{ab, bc, ca}});
    }
    f = std::move(finer);
  }
  for (auto& p : v) {
    p = p / std::pow(p.cwiseAbs().array().cube().sum(), 1.0 / 3.0);
    p = p.cwiseProduct(Eigen::Vector3d(0.030, 0.022, 0.016));
    p.z() = std::max(p.z(), -0.010);
  }
}

/// The unit cube's 8 corners and 12 outward triangles.
void cube(std::vector<Eigen::Vector3d>& v, std::vector<Tri>& f, double s = 0.02) {
  for (int c = 0; c < 8; ++c) v.emplace_back(s * (c & 1), s * ((c >> 1) & 1), s * ((c >> 2) & 1));
  f = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
}

std::string off(const std::vector<Eigen::Vector3d>& v, const std::vector<Tri>& f) {
  std::ostringstream o;
  o.precision(17);
  o << "OFF\n" << v.size() << " " << f.size() << " 0\n";
  for (const auto& p : v) o << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : f) o << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return o.str();
}

/// Two 2 cm cubes, the second moved by `offset`, as one OFF file.
std::string two_cubes(const Eigen::Vector3d& offset) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  cube(v, f);
  const std::vector<Tri> one = f;
  for (int c = 0; c < 8; ++c) v.push_back(v[static_cast<std::size_t>(c)] + offset);
  for (const auto& t : one) f.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  return off(v, f);
}

std::string obj(const std::vector<Eigen::Vector3d>& v, const std::vector<Tri>& f) {
  std::ostringstream o;
  o.precision(17);
  for (const auto& p : v) o << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : f) o << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  return o.str();
}

std::string ply(const std::vector<Eigen::Vector3d>& v, const std::vector<Tri>& f) {
  std::ostringstream o;
  o.precision(17);
  o << "ply\nformat ascii 1.0\nelement vertex " << v.size() << "\nproperty double x\nproperty double y\n"
    << "property double z\nelement face " << f.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& p : v) o << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : f) o << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return o.str();
}

std::string stl_binary(const std::vector<Eigen::Vector3d>& v, const std::vector<Tri>& f) {
  std::string s(80, '\0');
  const auto n = static_cast<std::uint32_t>(f.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : f) {
    float rec[12] = {};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) rec[3 + 3 * k + d] = static_cast<float>(v[static_cast<std::size_t>(t[k])][d]);
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  return s;
}

std::string stl_ascii(const std::vector<Eigen::Vector3d>& v, const std::vector<Tri>& f) {
  std::ostringstream o;
  o.precision(9);
  o << "solid t\n";
  for (const auto& t : f) {
    o << " facet normal 0 0 0\n  outer loop\n";
    for (int k : t) o << "   vertex " << v[k].x() << " " << v[k].y() << " " << v[k].z() << "\n";
    o << "  endloop\n endfacet\n";
  }
  o << "endsolid t\n";
  return o.str();
}

std::filesystem::path write(const test::FreshDir& dir, const std::string& name, const std::string& content) {
  const auto p = dir / name;
  std::ofstream(p, std::ios::binary) << content;
  return p;
}

/// The volume a closed outward surface encloses (divergence theorem).
double enclosed_volume(const Surface& s) {
  double v = 0;
  for (const auto& t : s.triangles) v += s.points[t[0]].dot(s.points[t[1]].cross(s.points[t[2]])) / 6;
  return v;
}

double area(const Surface& s) {
  double a = 0;
  for (const auto& t : s.triangles)
    a += 0.5 * (s.points[t[1]] - s.points[t[0]]).cross(s.points[t[2]] - s.points[t[0]]).norm();
  return a;
}

double volume(const Mesh3& m) {
  double v = 0;
  for (const auto& c : m.cells) v += signed_measure(m, c);
  return v;
}

TEST(Surface, EveryFormatReadsTheSameSurface) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  torus(v, f);
  const test::FreshDir dir;
  for (const auto& [name, content] : std::vector<std::pair<std::string, std::string>>{{"t.off", off(v, f)},
                                                                                      {"t.obj", obj(v, f)},
                                                                                      {"t.ply", ply(v, f)},
                                                                                      {"t.stl", stl_binary(v, f)},
                                                                                      {"ta.stl", stl_ascii(v, f)}}) {
    SCOPED_TRACE(name);
    const Surface s = read_surface(write(dir, name, content));
    EXPECT_EQ(s.points.size(), v.size()) << "STL's repeated corners are merged";
    EXPECT_EQ(s.triangles.size(), f.size());
    EXPECT_EQ(s.reoriented, 0);
    // The polyhedron's volume is 2 pi^2 R r^2 less the chords' share: an inscribed k-gon keeps
    // sin(2 pi / k) / (2 pi / k) of the circle's area, per circle direction (48 and 24 sides).
    const double exact = 2 * std::numbers::pi * std::numbers::pi * 0.03 * 0.012 * 0.012;
    auto lost = [](int k) { return 1 - std::sin(2 * std::numbers::pi / k) / (2 * std::numbers::pi / k); };
    EXPECT_NEAR(enclosed_volume(s), exact * (1 - lost(48) - lost(24)), exact * lost(48) * lost(24) * 4)
        << "the single-precision STL moves it by ~1e-7 relative, well inside";
  }
}

/// The slab's bounds on a surface meshed to 3,000 nodes (docs/meshes.md): the count within 15 %,
/// dihedral angles >= 10 deg (exudation's sliver bound), radius-edge <= 2 (the cell criterion).
Mesh3 mesh_3000_with_the_slabs_quality(const Surface& s) {
  Mesh3 m = mesh_surface(s, 3000, 0);
  EXPECT_NEAR(m.num_nodes(), 3000, 0.15 * 3000) << "the node-count rule: within 15 %";
  const MeshQuality q = mesh_quality(m);
  EXPECT_GE(q.min_angle, 10.0) << "exudation's sliver bound";
  EXPECT_LE(q.max_radius_edge, 2.0) << "the cell criterion";
  EXPECT_EQ(q.inverted, 0);
  return m;
}

TEST(Surface, MeshesToANodeCountWithTheSlabsQuality) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  torus(v, f);
  const test::FreshDir dir;
  const Surface s = read_surface(write(dir, "t.stl", stl_binary(v, f)));
  const Mesh3 m = mesh_3000_with_the_slabs_quality(s);
  // Mesh_3 keeps every surface facet within the facet distance (size / 10) of the input
  // surface, so the volumes differ by at most area x that distance; the size is about the
  // cube root of volume x sqrt(2) / nodes x 1.6 (the node-count rule's first guess, +-50 %).
  const double h = 1.5 * 1.6 * std::cbrt(enclosed_volume(s) * std::sqrt(2.0) / 3000);
  EXPECT_NEAR(volume(m), enclosed_volume(s), area(s) * h / 10);
  EXPECT_EQ(m.groups.at("surface").facets.size(), boundary_facets(m).size());
}

TEST(Surface, ACellThatExudationLeavesAboveTheRadiusEdgeBoundIsRemeshed) {
  // On this dome (binary STL) Mesh_3 meets the radius-edge criterion 2 while it refines, and
  // the perturbation and exudation after it left one cell at 2.017; run_mesh_3 then remakes the
  // mesh with the criterion tightened (docs/meshes.md). The bounds are the slab's, as above.
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  dome(v, f);
  const test::FreshDir dir;
  mesh_3000_with_the_slabs_quality(read_surface(write(dir, "dome.stl", stl_binary(v, f))));
}

TEST(Surface, SharpEdgesBoundOnePatchGroupPerFace) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  cube(v, f);
  const test::FreshDir dir;
  const Mesh3 m = mesh_surface(read_surface(write(dir, "c.off", off(v, f))), 0, 0.004);
  int patches = 0;
  for (const auto& [name, g] : m.groups) {
    if (name.rfind("patch_", 0) != 0) continue;
    ++patches;
    // Every node of a face's patch lies on that face's plane: one coordinate is 0 or 0.02.
    bool on_one_plane = false;
    for (int d = 0; d < 3; ++d)
      for (double c : {0.0, 0.02}) {
        bool all = true;
        for (int i : g.nodes) all = all && std::abs(m.points(d, i) - c) < 1e-12;
        on_one_plane = on_one_plane || all;
      }
    EXPECT_TRUE(on_one_plane) << name;
  }
  EXPECT_EQ(patches, 6);
  EXPECT_NEAR(volume(m), 8e-6, 1e-15) << "a polyhedron with its edges kept is meshed exactly";
}

TEST(Surface, CoplanarTrianglesThatShareAVertexAreNotACrossing) {
  // A CAD-style cylinder: with floating-point predicates the self-intersection test refused it
  // ("faces 916 and 914 cross", two stacked triangles of one side strip); it is closed and
  // simple, so it reads, in either format, and meshes with one patch per face its rims bound.
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  cylinder(v, f);
  const test::FreshDir dir;
  const Surface a = read_surface(write(dir, "cyl.stl", stl_binary(v, f)));
  const Surface b = read_surface(write(dir, "cyl.off", off(v, f)));
  EXPECT_EQ(a.triangles.size(), f.size());
  EXPECT_EQ(b.triangles.size(), f.size());
  const Mesh3 m = mesh_surface(b, 0, 0.006);
  int patches = 0;
  for (const auto& g : m.groups) patches += g.first.rfind("patch_", 0) == 0;
  EXPECT_EQ(patches, 3) << "top, bottom and side";
}

TEST(Surface, InwardAndInconsistentFacesAreReoriented) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  cube(v, f);
  auto inward = f;
  for (auto& t : inward) std::swap(t[1], t[2]);
  auto one = f;
  std::swap(one[0][1], one[0][2]);
  const test::FreshDir dir;
  const Surface a = read_surface(write(dir, "in.off", off(v, inward)));
  EXPECT_EQ(a.reoriented, 12);
  EXPECT_NEAR(enclosed_volume(a), 8e-6, 1e-18);
  const Surface b = read_surface(write(dir, "one.off", off(v, one)));
  EXPECT_EQ(b.reoriented, 1);
  EXPECT_NEAR(enclosed_volume(b), 8e-6, 1e-18);
}

/// The refusal: one InputError line naming the file and `what`.
void expect_refused(const std::filesystem::path& file, const std::string& what) {
  try {
    read_surface(file);
    ADD_FAILURE() << file << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

TEST(Surface, BadSurfacesAreRefusedWithOneLine) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  cube(v, f);
  const test::FreshDir dir;
  auto open = f;
  open.pop_back();
  expect_refused(write(dir, "open.off", off(v, open)), "not closed");
  // Two cubes sharing an edge (four faces on it), a corner only, and overlapping.
  expect_refused(write(dir, "edge.off", two_cubes(Eigen::Vector3d(0.02, 0.02, 0))), "not manifold");
  expect_refused(write(dir, "corner.off", two_cubes(Eigen::Vector3d(0.02, 0.02, 0.02))), "not manifold");
  expect_refused(write(dir, "cross.off", two_cubes(Eigen::Vector3d(0.01, 0.01, 0.01))), "self-intersecting");
  expect_refused(write(dir, "empty.off", ""), "empty");
  const std::string stl = stl_binary(v, f);
  expect_refused(write(dir, "cut.stl", stl.substr(0, stl.size() - 30)), "truncated");
  expect_refused(write(dir, "huge.off", "OFF\n1000000000 2000000000 0\n0 0 0\n"), "bytes");
  expect_refused(write(dir, "huge.ply",
                       "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                       "property float x\nend_header\n"),
                 "bytes");
  auto flat = f;
  flat[0] = {0, 1, 1};
  expect_refused(write(dir, "flat.off", off(v, flat)), "degenerate");
  auto line = v;
  line[2] = Eigen::Vector3d(0.01, 0, 0); // corner 2 onto the edge 0-1: face {0, 2, 1} has no area
  expect_refused(write(dir, "line.off", off(line, f)), "degenerate");
  auto range = f;
  range[0] = {0, 2, 99};
  expect_refused(write(dir, "range.off", off(v, range)), "not a readable off surface");
  expect_refused(write(dir, "garbage.obj", "this is not a surface\n"), "");
  expect_refused(dir / "absent.off", "cannot open");
  expect_refused(write(dir, "a.dxf", off(v, f)), "unknown surface format");
}

TEST(Surface, PolygonsAreSplitIntoTrianglesThatKeepTheirShape) {
  // An L-shaped prism (2 x 2 cm L of 1 cm arms, 1 cm tall): two non-convex hexagon caps and six
  // quad sides. The split must stay inside each polygon, so the body encloses exactly the L's
  // area times the height.
  const double s = 0.01;
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {2 * s, 0}, {2 * s, s}, {s, s}, {s, 2 * s}, {0, 2 * s}};
  std::vector<Eigen::Vector3d> p;
  for (double z : {0.0, s})
    for (const auto& q : l) p.emplace_back(q.x(), q.y(), z);
  std::vector<std::vector<std::size_t>> faces = {{5, 4, 3, 2, 1, 0}, {6, 7, 8, 9, 10, 11}};
  for (std::size_t i = 0; i < 6; ++i) faces.push_back({i, (i + 1) % 6, (i + 1) % 6 + 6, i + 6});
  const Surface b = checked_surface(p, faces, "L");
  EXPECT_EQ(b.triangles.size(), 2u * 4 + 6 * 2);
  EXPECT_EQ(b.reoriented, 0);
  // 20 triangles' triple products in doubles: rounding, far below one part in 10^12.
  EXPECT_NEAR(enclosed_volume(b), 3 * s * s * s, 3 * s * s * s * 1e-12);
}

TEST(Surface, APolygonListedTwiceIsRefusedAsCrossingItself) {
  // What the surface fuzzer found: one non-planar heptagon listed twice (a closed "pillow" of two
  // faces, every edge used twice). With CGAL's default split (a constrained Delaunay
  // triangulation in the polygon's projection plane) the first reached the triangle copy-out
  // with seven corners in one face, and the second is undefined behaviour inside CGAL's CDT.
  // Split by hole filling, the two sheets lie on each other: refused as self-intersecting.
  const std::vector<std::size_t> hepta = {3, 8, 12, 10, 11, 15, 13};
  // The two pillows' 16 corners (x, y, z after each other), as the fuzzer's bytes decode.
  const int pillows[2][48] = {{0, 0,  0, 2, 0, 0,  0, 2, 0, 2,  2, 0, 0, 0,  -7, -8, 0, 2,  0, 2, 2, -5, 1, 2,
                               3, -5, 4, 7, 6, -5, 5, 5, 6, -5, 0, 1, 4, -5, 1,  5,  4, -5, 2, 6, 3, -5, 3, 6},
                              {0, 0, 0, -3, 0, 7,  1, 6, -4, -5, -6, -3, -5, 0, -7, -8, 0, 2, 0, 2,  2, -5, 1, 2,
                               3, 1, 6, -4, 6, -5, 1, 6, 5,  -5, 5,  0,  -4, 4, -2, 0,  6, 4, 2, -5, 3, -5, 3, 6}};
  for (const auto& xyz : pillows) try {
      std::vector<Eigen::Vector3d> p;
      for (int i = 0; i < 16; ++i) p.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      checked_surface(p, {hepta, hepta}, "pillow");
      ADD_FAILURE() << "the pillow was accepted";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("pillow: self-intersecting", 0), 0u) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
}

TEST(Grading, TheSizeGrowsFromTheRefinementToTheBodys) {
  const std::vector<Refinement> r{{Eigen::Vector3d(0, 0, 0), 0.01, 0.001}};
  EXPECT_EQ(graded_size(Eigen::Vector3d(0.005, 0, 0), 0.01, r), 0.001);
  EXPECT_DOUBLE_EQ(graded_size(Eigen::Vector3d(0.02, 0, 0), 0.01, r), 0.001 + kRefineGrowth * 0.01);
  EXPECT_EQ(graded_size(Eigen::Vector3d(1, 0, 0), 0.01, r), 0.01);
  EXPECT_FALSE(refinement_error({Eigen::Vector3d(0, 0, 0), -1, 0.001}).empty());
  EXPECT_FALSE(refinement_error({Eigen::Vector3d(0, 0, 0), 1, 0}).empty());
  // A refinement's own growth: at 0.2 the size reaches the body's (H - h) / 0.2 beyond R.
  const std::vector<Refinement> slow{{Eigen::Vector3d(0, 0, 0), 0.01, 0.001, 0.2}};
  EXPECT_DOUBLE_EQ(graded_size(Eigen::Vector3d(0.02, 0, 0), 0.01, slow), 0.001 + 0.2 * 0.01);
  EXPECT_EQ(graded_size(Eigen::Vector3d(0.01 + 0.009 / 0.2 + 1e-9, 0, 0), 0.01, slow), 0.01);
  EXPECT_LT(graded_size(Eigen::Vector3d(0.01 + 0.009 / 0.2 - 1e-4, 0, 0), 0.01, slow), 0.01);
  EXPECT_FALSE(refinement_error({Eigen::Vector3d(0, 0, 0), 1, 0.001, 0}).empty());
  EXPECT_FALSE(refinement_error({Eigen::Vector3d(0, 0, 0), 1, 0.001, 1.5}).empty());
}

/// The mean edge length of the cells whose centroid lies within `r` of `c` (or beyond, `inside` false).
double mean_edge(const Mesh3& m, const Eigen::Vector3d& c, double r, bool inside) {
  double sum = 0;
  int n = 0;
  for (const auto& cell : m.cells) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int i : cell) g += m.points.col(i) / 4;
    if (((g - c).norm() <= r) != inside) continue;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) sum += (m.points.col(cell[a]) - m.points.col(cell[b])).norm(), ++n;
  }
  return n > 0 ? sum / n : 0;
}

TEST(Grading, AGradedSurfaceIsFineNearThePointAndCoarseAway) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Tri> f;
  torus(v, f);
  const test::FreshDir dir;
  const Surface s = read_surface(write(dir, "t.off", off(v, f)));
  const Eigen::Vector3d top(0.03, 0, 0.012);
  const double h = 0.0015, H = 0.006, R = 0.008;
  const Mesh3 graded = mesh_surface(s, 0, H, {{top, R, h}});
  const Mesh3 fine = mesh_surface(s, 0, h);
  // Within R the graded mesh has the fine mesh's size (the same criteria there); 15 % allows
  // for the cells at R's rim, which grow toward the body's size.
  EXPECT_LT(mean_edge(graded, top, R, true), 1.15 * mean_edge(fine, top, R, true));
  // Beyond the grading's reach ((H - h) / growth past R) the size is H's.
  EXPECT_GT(mean_edge(graded, top, R + (H - h) / kRefineGrowth, false), 2 * h);
  EXPECT_LT(graded.num_nodes(), fine.num_nodes() / 4);
  const MeshQuality q = mesh_quality(graded);
  EXPECT_GE(q.min_angle, 10.0);
  EXPECT_LE(q.max_radius_edge, 2.0);
}

TEST(Grading, ASlabRefinedAtItsEndKeepsItsCountAndQuality) {
  const Eigen::Vector3d end(0.2, 0.025, 0.02);
  const Mesh3 m = mesh_solid("slab", 2000, {{end, 0.01, 0.002}});
  EXPECT_NEAR(m.num_nodes(), 2000, 0.15 * 2000);
  EXPECT_LT(mean_edge(m, end, 0.01, true), 0.5 * mean_edge(m, end, 0.05, false));
  EXPECT_GE(mesh_quality(m).min_angle, 10.0);
}

TEST(Grading, AGradedMeshIsTheSameOnEveryRun) {
  // CGAL bounds the sliver perturbation by the time the refinement took unless told otherwise;
  // on the example bean graded at the default growth the perturbation outlasts it, and 6 runs
  // of `vtb mesh generate` gave 4 different meshes (37 of 1,354 nodes moved). With no time
  // limit the mesh depends on its input only. Two meshings, the second beside a thread that
  // keeps a core busy: identical to the bit. With the limit left to CGAL this failed 5 runs of
  // 5; it rests on timing, so a regression could slip through a run, never fail a correct one.
  const Surface s = read_surface(std::filesystem::path(VTB_SOURCE_DIR) / "meshes" / "data" / "bean.off");
  const std::vector<Refinement> r{{Eigen::Vector3d(0, 0.008, 0.024), 0.012, 0.0015}};
  const Mesh3 a = mesh_surface(s, 0, 0.005, r);
  std::atomic<bool> stop = false;
  std::thread busy([&] {
    volatile double x = 0;
    while (!stop) x = x + 1;
  });
  const Mesh3 b = mesh_surface(s, 0, 0.005, r);
  stop = true;
  busy.join();
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.cells, b.cells);
}

} // namespace
} // namespace vtb
