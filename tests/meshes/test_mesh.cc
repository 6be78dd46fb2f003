// Structured generators, mesh checks and region selection.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/region.hh"

#include <gtest/gtest.h>

namespace vtb {
namespace {

TEST(Generate, RectangleCountsAreaOrientationAndGroups) {
  const Mesh2 m = generate_rectangle({0.2, 0.05}, {8, 3});
  EXPECT_EQ(m.num_nodes(), 9 * 4);
  EXPECT_EQ(m.num_cells(), 2 * 8 * 3);
  double area = 0;
  for (const auto& c : m.cells) {
    EXPECT_GT(signed_measure(m, c), 0.0);
    area += signed_measure(m, c);
  }
  EXPECT_NEAR(area, 0.2 * 0.05, 1e-15);
  EXPECT_EQ(boundary_facets(m).size(), 2u * (8 + 3));
  EXPECT_EQ(m.groups.at("left").nodes.size(), 4u);
  EXPECT_EQ(m.groups.at("left").facets.size(), 3u);
  EXPECT_EQ(m.groups.at("top").facets.size(), 8u);
}

TEST(Generate, RectangleDiagonalsAlternate) {
  // Union jack: neighbouring squares use mirrored diagonals, so both diagonal directions
  // appear equally often on an even grid.
  const Mesh2 m = generate_rectangle({1, 1}, {4, 4});
  int rising = 0, falling = 0;
  for (const auto& e : unique_edges(m)) {
    const Eigen::Vector2d d = m.points.col(e[1]) - m.points.col(e[0]);
    if (std::abs(d.x()) > 1e-12 && std::abs(d.y()) > 1e-12) (d.x() * d.y() > 0 ? rising : falling)++;
  }
  EXPECT_EQ(rising, 8);
  EXPECT_EQ(falling, 8);
}

TEST(Generate, BoxIsConformingWithPositiveTetrahedra) {
  const Mesh3 m = generate_box({0.3, 0.2, 0.1}, {3, 2, 2});
  EXPECT_EQ(m.num_nodes(), 4 * 3 * 3);
  EXPECT_EQ(m.num_cells(), 6 * 3 * 2 * 2);
  double vol = 0;
  for (const auto& c : m.cells) {
    EXPECT_GT(signed_measure(m, c), 0.0);
    vol += signed_measure(m, c);
  }
  EXPECT_NEAR(vol, 0.3 * 0.2 * 0.1, 1e-15);
  // Conforming: only the outer squares' two triangles each are boundary facets.
  EXPECT_EQ(boundary_facets(m).size(), 2u * 2 * (3 * 2 + 2 * 2 + 3 * 2));
  EXPECT_EQ(m.groups.at("back").facets.size(), 2u * 3 * 2);
}

TEST(Generate, RefusesBadRequests) {
  EXPECT_THROW(generate_rectangle({0.0, 1.0}, {2, 2}), InputError);
  EXPECT_THROW(generate_box({1, 1, 1}, {1, 0, 1}), InputError);
}

Mesh2 two_triangles() {
  Mesh2 m;
  m.source = "t.msh";
  m.points.resize(2, 4);
  m.points << 0, 1, 1, 0, 0, 0, 1, 1;
  m.cells = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

std::string check_message(Mesh2 m) {
  try {
    check_and_orient(m);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckMesh, RefusesEachClassOfBrokenMesh) {
  Mesh2 m = two_triangles();
  m.cells[1] = {0, 2, 7};
  EXPECT_EQ(check_message(m), "t.msh: cell 1 refers to node 7, out of range [0, 4)");
  m = two_triangles();
  m.cells[1] = {0, 2, 2};
  EXPECT_EQ(check_message(m), "t.msh: cell 1 repeats a vertex");
  m = two_triangles();
  m.cells.push_back({2, 0, 1});
  EXPECT_EQ(check_message(m), "t.msh: cell 2 duplicates an earlier cell");
  m = two_triangles();
  m.points(0, 3) = 0.5;
  m.points(1, 3) = 0.5; // on the diagonal 0-2: zero area
  EXPECT_EQ(check_message(m), "t.msh: cell 1 has zero area (degenerate)");
  m = two_triangles();
  m.points(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(check_message(m), "t.msh: node 2 has a non-finite coordinate");
  m = two_triangles();
  m.cells.pop_back();
  EXPECT_EQ(check_message(m), "t.msh: node 3 belongs to no cell");
}

TEST(CheckMesh, ReorientsInvertedCells) {
  Mesh2 m = two_triangles();
  m.cells[0] = {0, 2, 1};
  EXPECT_EQ(check_and_orient(m), 1);
  EXPECT_GT(signed_measure(m, m.cells[0]), 0.0);
}

TEST(Region, BoxGroupAndPointSelection) {
  const Mesh2 m = generate_rectangle({0.2, 0.05}, {4, 2});
  RegionSpec<2> box;
  box.box = Box<2>{{0.2, 0.0}, {0.2, 0.05}};
  const Selection<2> s = select(m, box, "load");
  EXPECT_EQ(s.nodes.size(), 3u);
  EXPECT_EQ(s.facets.size(), 2u);
  RegionSpec<2> pt;
  pt.point = Eigen::Vector2d(0.11, 0.026);
  // The lattice's nodes are 0.05 x 0.025 apart: (0.1, 0.025) is the nearest to (0.11, 0.026),
  // by coordinates (not by asking nearest_node again).
  const auto picked = select(m, pt, "probe").nodes;
  ASSERT_EQ(picked.size(), 1u);
  EXPECT_NEAR(m.points(0, picked[0]), 0.1, 1e-15);
  EXPECT_NEAR(m.points(1, picked[0]), 0.025, 1e-15);
  for (int i = 0; i < m.num_nodes(); ++i)
    EXPECT_GE((m.points.col(i) - Eigen::Vector2d(0.11, 0.026)).norm(),
              (m.points.col(picked[0]) - Eigen::Vector2d(0.11, 0.026)).norm());
  RegionSpec<2> grp;
  grp.group = "nope";
  EXPECT_THROW(select(m, grp, "fix"), InputError);
}

} // namespace
} // namespace vtb
