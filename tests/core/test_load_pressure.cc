// How hard a scene's loads press (load_pressure.hh), and what `springs = "auto"` builds from it
// (docs/volume_term.md, "What auto builds").
#include "support/fresh_dir.hh"
#include "vtb/meshes/region.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/load_pressure.hh"
#include "vtb/springs/model.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

namespace vtb {
namespace {

/// A 40 x 40 x 20 mm box (8 x 8 x 4 cells), E 5 kPa, clamped at its base and loaded on a 10 mm
/// disc at the centre of its top by `force` (N, as TOML), springs `springs`.
Scene disc_block(const std::string& force, const std::string& springs = "auto") {
  return parse_scene(R"(
[scene]
duration = 0.1
output_interval = 0.01
[mesh]
generate = { shape = "box", size = [0.04, 0.04, 0.02], divisions = [8, 8, 4] }
[material]
young_modulus = 5.0e3
poisson_ratio = 0.45
density = 1000.0
retardation_time = 0.05
[[fix]]
group = "z_min"
[[load]]
disc = { center = [0.02, 0.02, 0.02], radius = 0.01 }
total_force = [)" + force +
                         R"(]
[solver]
kind = "implicit-euler"
dt = 0.001
springs = ")" + springs + R"("
)",
                     "disc_block.toml", ".");
}

/// The scene's loads at their full value and their pressure in units of E, with the exact
/// pressure of the disc's traction: the force over the selected facets' area.
struct Pressed {
  double read = 0, exact = 0;
};
Pressed pressed(const Scene& scene) {
  const Problem<3> p = build_problem<3>(scene, std::get<Mesh3>(load_mesh(scene)));
  Nodal<3> f = Nodal<3>::Zero(3, p.num_nodes());
  p.external_forces(std::numeric_limits<double>::infinity(), f);
  RegionSpec<3> disc;
  disc.disc = Disc<3>{Vec<3>(0.02, 0.02, 0.02), 0.01};
  double area = 0;
  for (const auto& facet : select<3>(p.mesh, disc, "disc").facets) area += facet_measure<3>(p.mesh, facet);
  return {deepest_load_pressure<3>(p.mesh, Eigen::Map<const Eigen::VectorXd>(f.data(), f.size()), 5.0e3, 1.0),
          f.colwise().norm().sum() > 0 ? std::abs(f.row(2).sum()) / area / 5.0e3 : 0.0};
}

TEST(LoadPressure, ADiscReadsAsItsTractionAndOnlyWhereItPresses) {
  // A uniform traction p on flat facets puts p times its share of the facets' area on each node
  // of the patch: at an inner node of the patch the ratio is p itself, to rounding.
  const Pressed down = pressed(disc_block("0.0, 0.0, -0.1"));
  ASSERT_GT(down.exact, 0.0);
  EXPECT_NEAR(down.read, down.exact, 1e-12 * down.exact);
  // The same force pulling out of the body, or along its face, presses nothing.
  EXPECT_EQ(pressed(disc_block("0.0, 0.0, 0.1")).read, 0.0);
  EXPECT_NEAR(pressed(disc_block("0.1, 0.0, 0.0")).read, 0.0, 1e-12 * down.exact);
}

TEST(LoadPressure, AutoBuildsTheVolumeNetworkWhereALoadPressesDeep) {
  // The 10 mm disc's facets (300 mm^2): 0.2 N presses 0.13 E (past kDeepLoadPressure), 0.02 N a
  // tenth of it. auto builds the fitted volume per node under the first and says so, the pair springs
  // under the second; the scene's own choice is kept whatever the load.
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  const Scene deep = disc_block("0.0, 0.0, -0.2"), light = disc_block("0.0, 0.0, -0.02");
  ASSERT_GT(pressed(deep).read, kDeepLoadPressure);
  ASSERT_LT(pressed(light).read, kDeepLoadPressure);
  const Model<3> a = build_model<3>(deep, std::get<Mesh3>(load_mesh(deep)));
  EXPECT_EQ(a.net.calibration, "fitted-nodal");
  EXPECT_EQ(a.net.calibration_requested, "auto");
  EXPECT_NE(a.net.calibration_note.find("builds fitted-nodal"), std::string::npos) << a.net.calibration_note;
  EXPECT_FALSE(a.net.volume.empty());
  const Model<3> b = build_model<3>(light, std::get<Mesh3>(load_mesh(light)));
  EXPECT_EQ(b.net.calibration, "fitted");
  EXPECT_TRUE(b.net.volume.empty());
  const Scene kept = disc_block("0.0, 0.0, -0.2", "fitted");
  EXPECT_EQ(build_model<3>(kept, std::get<Mesh3>(load_mesh(kept))).net.calibration, "fitted");
  ::unsetenv("VTB_CACHE_DIR");
}

} // namespace
} // namespace vtb
