// Faces named by axis (x_min ... z_max): on every generated box, slab and rectangle, and on the
// canonical meshes read from file, each is the face the generators name by the plate's words
// (z_min = front: the base of a body whose up is z). Exact equality: the generators place a
// face's nodes on its plane, so both selections must hold the same nodes and facets.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/meshes/region.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/cgal_generate.hh"
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace vtb {
namespace {

template <int dim> Selection<dim> by_group(const Mesh<dim>& m, const std::string& name) {
  RegionSpec<dim> spec;
  spec.group = name;
  return select(m, spec, "fix[0]");
}

/// Facets compared as sets of vertex sets (a face's facets in any order, any orientation).
template <int dim> std::set<std::vector<int>> facet_set(const Selection<dim>& s) {
  std::set<std::vector<int>> out;
  for (const auto& f : s.facets) {
    std::vector<int> v(f.begin(), f.end());
    std::sort(v.begin(), v.end());
    out.insert(v);
  }
  return out;
}

template <int dim> void expect_faces_match_names(const Mesh<dim>& m) {
  const std::vector<std::pair<const char*, const char*>> pairs3 = {{"x_min", "left"},   {"x_max", "right"},
                                                                   {"y_min", "bottom"}, {"y_max", "top"},
                                                                   {"z_min", "front"},  {"z_max", "back"}};
  for (int i = 0; i < 2 * dim; ++i) {
    const auto& [axis_name, word] = pairs3[static_cast<std::size_t>(i)];
    ASSERT_TRUE(m.groups.count(word)) << m.source << " " << word;
    const Selection<dim> a = by_group(m, axis_name), b = by_group(m, word);
    std::vector<int> bn = b.nodes;
    std::sort(bn.begin(), bn.end());
    EXPECT_EQ(a.nodes, bn) << m.source << " " << axis_name;
    EXPECT_FALSE(a.facets.empty()) << m.source << " " << axis_name;
    EXPECT_EQ(facet_set(a), facet_set(b)) << m.source << " " << axis_name;
  }
}

TEST(AxisFaces, EqualTheNamedFacesOfAStructuredBoxAndRectangle) {
  expect_faces_match_names(generate_box({0.3, 0.2, 0.1}, {3, 2, 2}));
  expect_faces_match_names(generate_rectangle({0.2, 0.05}, {8, 3}));
}

TEST(AxisFaces, EqualTheNamedFacesOfTheCanonicalMeshFiles) {
  for (const char* f : {"slab_500.msh", "slab_2000.msh"}) {
    const AnyMesh m = read_msh(std::string(VTB_SOURCE_DIR) + "/meshes/data/" + f);
    std::visit([](const auto& mesh) { expect_faces_match_names(mesh); }, m);
  }
}

#ifdef VTB_HAVE_CGAL_MESHERS
TEST(AxisFaces, EqualTheNamedFacesOfAnUnstructuredBox) {
  expect_faces_match_names(mesh_box({0.06, 0.04, 0.03}, 400));
}
#endif

TEST(AxisFaces, ZBelongsTo3DAloneAndOnlyTheSixNamesAreFaces) {
  EXPECT_TRUE(axis_face_of("z_min", 3).has_value());
  EXPECT_FALSE(axis_face_of("z_min", 2).has_value());
  EXPECT_FALSE(axis_face_of("w_min", 3).has_value());
  EXPECT_FALSE(axis_face_of("x_mid", 3).has_value());
  const Mesh2 plate = generate_rectangle({0.2, 0.05}, {4, 2});
  EXPECT_THROW(by_group(plate, "z_min"), InputError); // a plate has no z face
}

TEST(AxisFaces, AMeshGroupOfTheSameNameWins) {
  Mesh3 m = generate_box({0.3, 0.2, 0.1}, {3, 2, 2});
  m.groups["z_min"] = m.groups.at("left");
  EXPECT_EQ(by_group(m, "z_min").nodes, m.groups.at("left").nodes);
}

TEST(AxisFaces, ACurvedBodysExtremeIsRefusedInOneLineNamingTheGroup) {
  const AnyMesh m = read_msh(std::string(VTB_SOURCE_DIR) + "/meshes/data/sphere_500.msh");
  try {
    by_group(std::get<Mesh3>(m), "z_min");
    FAIL() << "a sphere has no flat face at its lowest z";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fix[0]: group \"z_min\""), std::string::npos) << what;
    EXPECT_NE(what.find("no flat face"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

} // namespace
} // namespace vtb
