// .msh round trip through the gmsh API and refusal of broken files.
#include "support/fresh_dir.hh"
#include "vtb/base/input_error.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/msh_io.hh"

#include <gtest/gtest.h>

#include <ostream>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>

namespace vtb {
namespace {

/// A path in a folder of this test's own (fresh, removed when the test ends): tests that
/// write the same file name cannot race under ctest -j or read an old run's file.
std::filesystem::path temp(const std::string& name) {
  static thread_local std::unique_ptr<test::FreshDir> dir;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  static thread_local const void* owner = nullptr;
  if (!dir || owner != info) {
    dir = std::make_unique<test::FreshDir>();
    owner = info;
  }
  return *dir / name;
}

template <int dim> void expect_same(const Mesh<dim>& a, const Mesh<dim>& b) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_cells(), b.num_cells());
  // gmsh prints 16 significant digits: a round trip may move a coordinate by one unit in the
  // 16th digit, i.e. up to ~1e-16 relative; a few ulps of the largest coordinate bound it.
  EXPECT_LE((a.points - b.points).cwiseAbs().maxCoeff(),
            4 * std::numeric_limits<double>::epsilon() * a.points.cwiseAbs().maxCoeff());
  EXPECT_EQ(a.cells, b.cells);
  ASSERT_EQ(a.groups.size(), b.groups.size());
  for (const auto& [name, g] : a.groups) {
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

std::string read_error(const std::string& name, const std::string& text) {
  const auto path = temp(name);
  std::ofstream(path) << text;
  try {
    read_msh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const std::string kHeader = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const std::string kNodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n";

struct Broken {
  std::string name, text, expect;
};

/// Names the case in test output (gtest would otherwise dump the struct's raw bytes, padding
/// included, which valgrind reports as reads of uninitialised memory).
void PrintTo(const Broken& b, std::ostream* os) {
  *os << b.name;
}

class BrokenMsh : public ::testing::TestWithParam<Broken> {};

TEST_P(BrokenMsh, IsRefusedWithOneLineNamingFileAndProblem) {
  const auto& b = GetParam();
  const std::string msg = read_error(b.name + ".msh", b.text);
  EXPECT_EQ(msg.rfind(temp(b.name + ".msh").string() + ": ", 0), 0u) << msg;
  EXPECT_NE(msg.find(b.expect), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Classes, BrokenMsh,
    ::testing::Values(
        Broken{"empty", "", "no $MeshFormat header"},
        Broken{"garbage", "this is not a mesh\n", "no $MeshFormat header"},
        Broken{"version", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", "unsupported .msh version \"3.0\""},
        Broken{"no_nodes", kHeader, "missing $Nodes section"},
        Broken{"huge_nodes", kHeader + "$Nodes\n1000000000000000\n1 0 0 0\n$EndNodes\n$Elements\n0\n$EndElements\n",
               "$Nodes declares 1000000000000000 entries"},
        Broken{"huge_elements", kHeader + kNodes + "$Elements\n99999999999\n$EndElements\n",
               "$Elements declares 99999999999"},
        Broken{"sparse_tags",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 999999999999\n2 1 0 3\n1\n2\n999999999999\n0 0 "
               "0\n1 0 0\n0 1 0\n"
               "$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 999999999999\n$EndElements\n",
               "tag range"},
        Broken{"bad_header", kHeader + "$Nodes\nfour\n$EndNodes\n$Elements\n0\n$EndElements\n",
               "malformed header line"},
        Broken{"out_of_range", kHeader + kNodes + "$Elements\n1\n1 2 2 0 1 1 2 9\n$EndElements\n",
               "gmsh cannot read it"},
        Broken{"repeated_vertex", kHeader + kNodes + "$Elements\n1\n1 2 2 0 1 1 2 2\n$EndElements\n",
               "repeats a vertex"},
        Broken{"duplicate", kHeader + kNodes + "$Elements\n2\n1 2 2 0 1 1 2 3\n2 2 2 0 1 2 3 1\n$EndElements\n",
               "cell 1 duplicates an earlier cell"},
        Broken{"nan",
               kHeader +
                   "$Nodes\n3\n1 0 0 0\n2 nan 0 0\n3 0 1 0\n$EndNodes\n$Elements\n1\n1 2 2 0 1 1 2 3\n$EndElements\n",
               "non-finite"},
        Broken{"quad", kHeader + kNodes + "$Elements\n1\n1 3 2 0 1 1 2 3 4\n$EndElements\n", "unsupported element"},
        Broken{"truncated", kHeader + "$Nodes\n4\n1 0 0 0\n2 1 0", "missing $Elements section"}),
    [](const auto& pinfo) { return pinfo.param.name; });

TEST(MshIo, ReorientsInvertedCellsWithAWarning) {
  const auto path = temp("inverted.msh");
  std::ofstream(path) << kHeader << kNodes << "$Elements\n2\n1 2 2 0 1 1 3 2\n2 2 2 0 1 1 3 4\n$EndElements\n";
  ::testing::internal::CaptureStderr();
  const Mesh2 m = std::get<Mesh2>(read_msh(path));
  const std::string err = ::testing::internal::GetCapturedStderr();
  for (const auto& c : m.cells) EXPECT_GT(signed_measure(m, c), 0.0);
  // One of the two cells was inverted: the warning names the file and the count, on one line.
  EXPECT_NE(err.find("vtb: warning: " + path.string() + ": 1 inverted cells re-oriented\n"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

TEST(MshIo, RefusesMissingAndBrokenFiles) {
  try {
    read_msh("/nonexistent/x.msh");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/x.msh: cannot open mesh file");
  }
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

namespace vtb {
namespace {

TEST(MshIo, AFileThatCrashesGmshIsRefusedNotFatal) {
  // Found by fuzzing: gmsh 4.8 frees memory twice on this file and aborts. The reader runs
  // gmsh in a child process, so the caller gets one line and carries on.
  const auto file = std::filesystem::path(VTB_SOURCE_DIR) / "tests" / "meshes" / "data" / "gmsh_crash.msh";
  try {
    read_msh(file);
    FAIL() << "accepted a malformed file";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
  // The process is intact: a good file still reads.
  write_msh(generate_rectangle({1, 1}, {2, 2}), temp("after_crash.msh"));
  EXPECT_EQ(std::get<Mesh2>(read_msh(temp("after_crash.msh"))).num_nodes(), 9);
}

/// Whether this process has libgmsh mapped.
bool gmsh_loaded() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find("libgmsh") != std::string::npos) return true;
  return false;
}

TEST(MshIo, OnlyTheReadersChildLoadsGmsh) {
  // The gmsh API is a module (meshes/src/gmsh_backend.hh): a process that reads a .msh file
  // gets the mesh without libgmsh (and OpenCASCADE, ~40 MB resident) entering it; a write
  // loads it in the writing process. A fresh process each (gtest re-executes the binary for a
  // death test in "threadsafe" style), as an earlier test of this binary may have written.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto file = std::filesystem::path(VTB_SOURCE_DIR) / "meshes" / "data" / "slab_500.msh";
  EXPECT_EXIT(
      {
        const bool before = gmsh_loaded();
        const int nodes = std::get<Mesh3>(read_msh(file)).num_nodes();
        std::exit(!before && nodes == 458 && !gmsh_loaded() ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
  EXPECT_EXIT(
      {
        write_msh(generate_rectangle({1, 1}, {2, 2}), temp("written.msh"));
        std::exit(gmsh_loaded() ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

} // namespace
} // namespace vtb
