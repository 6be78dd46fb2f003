// .msh round trip through the gmsh API and refusal of broken files.
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/input_error.hh"
#include "vtb/meshes/msh_io.hh"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>

namespace vtb {
namespace {

std::filesystem::path temp(const std::string &name) {
  const auto dir = std::filesystem::temp_directory_path() / "vtb_tests";
  std::filesystem::create_directories(dir);
  return dir / name;
}

template <int dim> void expect_same(const Mesh<dim> &a, const Mesh<dim> &b) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_cells(), b.num_cells());
  // gmsh prints 16 significant digits: a round trip may move a coordinate by one unit in the
  // 16th digit, i.e. up to ~1e-16 relative; a few ulps of the largest coordinate bound it.
  EXPECT_LE((a.points - b.points).cwiseAbs().maxCoeff(),
            4 * std::numeric_limits<double>::epsilon() * a.points.cwiseAbs().maxCoeff());
  EXPECT_EQ(a.cells, b.cells);
  ASSERT_EQ(a.groups.size(), b.groups.size());
  for (const auto &[name, g] : a.groups) {
    ASSERT_TRUE(b.groups.count(name)) << name;
    EXPECT_EQ(g.nodes, b.groups.at(name).nodes) << name;
    EXPECT_EQ(g.facets.size(), b.groups.at(name).facets.size()) << name;
  }
}

TEST(MshIo, RoundTripsTrianglesAndTetrahedraWithGroups) {
  const Mesh2 plate = generate_rectangle({0.2, 0.05}, {6, 2});
  write_msh(plate, temp("plate.msh"));
  expect_same(plate, std::get<Mesh2>(read_msh(temp("plate.msh"))));
  const Mesh3 box = generate_box({0.1, 0.1, 0.05}, {2, 2, 1});
  write_msh(box, temp("box.msh"));
  expect_same(box, std::get<Mesh3>(read_msh(temp("box.msh"))));
}

std::string read_error(const std::string &name, const std::string &text) {
  const auto path = temp(name);
  std::ofstream(path) << text;
  try {
    read_msh(path);
  } catch (const InputError &e) {
    return e.what();
  }
  return "";
}

TEST(MshIo, RefusesMissingAndBrokenFiles) {
  try {
    read_msh("/nonexistent/x.msh");
    FAIL();
  } catch (const InputError &e) {
    EXPECT_STREQ(e.what(), "/nonexistent/x.msh: cannot open mesh file");
  }
  EXPECT_NE(read_error("garbage.msh", "this is not a mesh\n").find("garbage.msh"), std::string::npos);
  const std::string quad =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n"
      "$Elements\n1\n1 3 2 0 1 1 2 3 4\n$EndElements\n";
  const std::string msg = read_error("quad.msh", quad);
  EXPECT_NE(msg.find("quad.msh: unsupported element"), std::string::npos) << msg;
  EXPECT_NE(msg.find("(type 3)"), std::string::npos) << msg;
  const std::string degenerate =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 2 0 0\n$EndNodes\n"
      "$Elements\n1\n1 2 2 0 1 1 2 3\n$EndElements\n";
  EXPECT_EQ(read_error("degenerate.msh", degenerate),
            temp("degenerate.msh").string() + ": cell 0 has zero area (degenerate)");
}

} // namespace
} // namespace vtb
