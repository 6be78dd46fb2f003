// CGAL-generated meshes: the paper's plates (exact node counts, quality, bit-for-bit
// regeneration of the committed files) and the Mesh_3 solids.
#include "support/fresh_dir.hh"
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/meshes/quality.hh"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

namespace vtb {
namespace {

const std::filesystem::path kData = std::filesystem::path(VTB_SOURCE_DIR) / "meshes" / "data";

std::string bytes(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

class Plate : public ::testing::TestWithParam<int> {};

TEST_P(Plate, HasTheExactNodeCountQualityAndGroups) {
  const int n = GetParam();
  const Mesh2 m = mesh_polygon(paper_plate(), n);
  EXPECT_EQ(m.num_nodes(), n);
  const MeshQuality q = mesh_quality(m);
  EXPECT_GE(q.min_angle, 20.0) << "Delaunay refinement with B = 0.125 bounds angles below by 20.7 deg";
  EXPECT_EQ(q.inverted, 0);
  double area = 0;
  for (const auto& c : m.cells) area += signed_measure(m, c);
  EXPECT_NEAR(area, 0.2 * 0.05 - 2 * 0.5 * 0.05 * 0.0125, 1e-15) << "the polygon is meshed exactly";
  for (int i : m.groups.at("clamp").nodes) EXPECT_EQ(m.points(0, i), 0.0);
  for (int i : m.groups.at("load").nodes) EXPECT_NEAR(m.points(0, i), 0.2, 1e-15);
  EXPECT_GE(m.groups.at("clamp").facets.size(), 3u);
  EXPECT_GE(m.groups.at("load").facets.size(), 2u);
}

TEST_P(Plate, RegeneratesTheCommittedFileBitForBit) {
  const int n = GetParam();
  const test::FreshDir fresh;
  const auto out = fresh / ("plate_" + std::to_string(n) + ".msh");
  write_msh(mesh_polygon(paper_plate(), n), out);
  const auto committed = kData / ("plate_" + std::to_string(n) + ".msh");
  ASSERT_TRUE(std::filesystem::exists(committed)) << committed;
  EXPECT_TRUE(bytes(out) == bytes(committed)) << "scripts/make_meshes.sh must reproduce " << committed;
}

INSTANTIATE_TEST_SUITE_P(PaperSizes, Plate, ::testing::Values(517, 123));

TEST(Plate, RefusesImpossibleRequests) {
  EXPECT_THROW(mesh_polygon(paper_plate(), 2), InputError);
  Polygon line;
  line.vertices = {{0, 0}, {1, 0}};
  EXPECT_THROW(mesh_polygon(line, 10), InputError);
}

TEST(Plate, WithAHoleHasTheExactNodeCountQualityAndAnEmptyHole) {
  // A 10 x 5 cm rectangle with a central hole of radius 1.2 cm (a polygon with edges as long as the
  // mesh's, 26 here): exact node count, the refinement's angle bound, no cell in the hole, and the
  // hole's rim as group "hole" at the radius (its polygon's vertices on the circle, the
  // points the refinement puts on its sides inside it by at most r (1 - cos(pi / 16))).
  const double r = 0.012;
  const Mesh2 m = mesh_rectangle({0.1, 0.05}, 600, r);
  EXPECT_EQ(m.num_nodes(), 600);
  const MeshQuality q = mesh_quality(m);
  EXPECT_GE(q.min_angle, 20.0);
  EXPECT_EQ(q.inverted, 0);
  const Eigen::Vector2d centre(0.05, 0.025);
  double area = 0;
  for (const auto& c : m.cells) {
    area += signed_measure(m, c);
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    for (int v : c) g += m.points.col(v) / 3.0;
    EXPECT_GT((g - centre).norm(), 0.99 * r * std::cos(std::numbers::pi / 16)) << "a cell inside the hole";
  }
  const auto& hole = m.groups.at("hole");
  ASSERT_GE(hole.facets.size(), 16u);
  for (int v : hole.nodes) {
    EXPECT_LE((m.points.col(v) - centre).norm(), r * (1 + 1e-12));
    EXPECT_GE((m.points.col(v) - centre).norm(), r * std::cos(std::numbers::pi / 16));
  }
  // The hole is a polygon of n >= 16 sides inscribed in the circle: its area is between the
  // 16-gon's, 8 r^2 sin(pi / 8), and the circle's.
  EXPECT_LT(area, 0.1 * 0.05 - 8 * r * r * std::sin(std::numbers::pi / 8));
  EXPECT_GT(area, 0.1 * 0.05 - std::numbers::pi * r * r);
  for (const char* g : {"left", "right", "top", "bottom"}) EXPECT_GE(m.groups.at(g).facets.size(), 3u) << g;
  EXPECT_THROW(mesh_rectangle({0.1, 0.05}, 600, 0.021), InputError) << "a ligament under a tenth of the side";
}

TEST(Solid, SlabHasItsVolumeQualityAndFaceGroups) {
  const Mesh3 m = mesh_solid("slab", 500);
  EXPECT_NEAR(m.num_nodes(), 500, 75) << "node count within 15 %";
  const MeshQuality q = mesh_quality(m);
  EXPECT_GE(q.min_angle, 10.0) << "slivers exuded to a 10 deg dihedral bound";
  EXPECT_LE(q.max_radius_edge, 2.0 + 1e-9) << "Mesh_3 cell criterion";
  double vol = 0;
  for (const auto& c : m.cells) vol += signed_measure(m, c);
  EXPECT_NEAR(vol, 0.2 * 0.05 * 0.02, 1e-12 * 0.2 * 0.05 * 0.02) << "planar faces and protected edges: exact volume";
  for (const char* g : {"left", "right", "bottom", "top", "front", "back"})
    EXPECT_FALSE(m.groups.at(g).facets.empty()) << g;
}

TEST(Solid, SphereSurfaceNodesLieOnTheSphere) {
  const Mesh3 m = mesh_solid("sphere", 500);
  const MeshQuality q = mesh_quality(m);
  EXPECT_GE(q.min_angle, 10.0);
  EXPECT_LE(q.max_radius_edge, 2.0 + 1e-9);
  // Surface points are projected on the implicit surface to relative error 1e-8.
  for (int i : m.groups.at("surface").nodes) EXPECT_NEAR(m.points.col(i).norm(), 0.05, 1e-6 * 0.05);
}

TEST(Solid, CommittedMeshesLoad) {
  for (const char* f : {"slab_500.msh", "slab_2000.msh", "sphere_500.msh", "sphere_2000.msh"}) {
    const Mesh3 m = std::get<Mesh3>(read_msh(kData / f));
    EXPECT_GT(m.num_nodes(), 400) << f;
    EXPECT_EQ(mesh_quality(m).inverted, 0) << f;
  }
}

} // namespace
} // namespace vtb
