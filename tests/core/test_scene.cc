// Scene files: every bad input is refused with one line naming the file, the key and the problem.
#include "support/fresh_dir.hh"
#include "support/small_models.hh"
#include "vtb/springs/model.hh"

#include <gtest/gtest.h>

#include <fstream>
#include <ostream>

namespace vtb {
namespace {

const std::string kGood = test::plate_scene(4, 2, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [1.0, 0.0]
[[probe]]
name = "tip"
point = [0.2, 0.025]
[solver]
kind = "filtered"
dt = 1e-3
[haptics]
max_force = 4.0
[haptics.hand]
waypoints = [[0.05, 0.08], [0.05, 0.04]]
duration = 1.0
grip_stiffness = 2000.0
)");

/// Replaces the first occurrence of `from` in the good scene.
std::string with(const std::string& from, const std::string& to) {
  std::string s = kGood;
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

/// The message of the InputError that parsing and building throw, or "" if none.
std::string error_of(const std::string& text) {
  try {
    const Scene s = parse_scene(text, "bad.toml", ".");
    build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
    return msg;
  }
  return "";
}

TEST(Scene, GoodSceneParses) {
  const Scene s = parse_scene(kGood, "good.toml", ".");
  EXPECT_EQ(s.name, "plate");
  EXPECT_EQ(s.solver.step.filter, "auto"); // the design's default: the integrator picks the filter
  EXPECT_EQ(s.solver.step.strain_limit, 0.0);
  EXPECT_EQ(error_of(kGood), "");
}

struct BadCase {
  std::string from, to, expect;
};

std::ostream& operator<<(std::ostream& os, const BadCase& c) {
  return os << "'" << c.from << "' -> '" << c.to << "'";
}

class BadScene : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadScene, IsRefusedWithAPreciseMessage) {
  const auto& c = GetParam();
  const std::string msg = error_of(with(c.from, c.to));
  EXPECT_NE(msg.find("bad.toml"), std::string::npos) << msg;
  EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadScene,
    ::testing::Values(
        BadCase{"young_modulus =", "youngs_modulus =",
                "[material].youngs_modulus: unknown key; did you mean 'young_modulus'?"},
        BadCase{"poisson_ratio = 0.3333", "poisson_ratio = 0.5",
                "[material].poisson_ratio: = 0.5: must be in [0, 0.5)"},
        BadCase{"density = 1000.0", "density = -1.0", "[material].density: = -1: must be > 0"},
        BadCase{"density = 1000.0", "density = nan", "[material].density: must be finite"},
        BadCase{"dt = 1e-3", "dt = 0.0", "[solver].dt: = 0: must be > 0"},
        BadCase{"dt = 1e-3", "dt = -1e-3", "[solver].dt: = -0.001: must be > 0"},
        BadCase{"kind = \"filtered\"", "kind = \"filterd\"", "[solver].kind: = \"filterd\": must be one of"},
        BadCase{"group = \"left\"", "group = \"lefty\"", "group \"lefty\" is not in mesh"},
        BadCase{"group = \"left\"", "box = [[5.0, 5.0], [6.0, 6.0]]", "the region selects no node"},
        BadCase{"total_force = [1.0, 0.0]", "total_force = [1.0, 0.0, 0.0]", "has 3 components; the mesh is 2D"},
        BadCase{"total_force = [1.0, 0.0]", "total_force = \"big\"", "total_force: must be an array of numbers"},
        BadCase{"duration = 1.0", "duration = 1.0\nduration = 2.0", "TOML syntax"},
        BadCase{"[[probe]]", "[[probe]]\nname = \"tip\"\npoint = [0.0, 0.0]\n[[probe]]",
                "probe name \"tip\" is used twice"},
        BadCase{"point = [0.2, 0.025]", "point = [0.2, 0.025]\nload = \"push\"",
                "[[probe]] #1: needs exactly one of point, load"},
        BadCase{"point = [0.2, 0.025]", "load = \"psuh\"", "probe \"tip\".load: no [[load]] is named \"psuh\""},
        BadCase{"group = \"left\"", "group = \"left\"\npoint = [0.0, 0.0]", "needs exactly one of box, group, point"},
        BadCase{"generate = {", "file = \"missing.msh\"\n#", "missing.msh: cannot open mesh file"},
        BadCase{"[[fix]]\ngroup = \"left\"",
                "[[fix]]\ngroup = \"left\"\n[[drive]]\ngroup = \"left\"\ndisplacement = [0.0, 0.001]",
                "both constrain node"},
        BadCase{"output_interval = 0.01", "output_interval = 5.0", "must not exceed [scene].duration"},
        BadCase{"[solver]", "[solvr]", "unknown key; did you mean 'solver'?"},
        // Found by fuzzing: integers beyond 2^53 are numbers toml++ will not convert.
        BadCase{"young_modulus = 5.0e4", "young_modulus = 9007199254740993",
                "[material].young_modulus: must be a number a double can hold exactly"},
        BadCase{"total_force = [1.0, 0.0]", "total_force = [9007199254740993, 0.0]",
                "total_force: entry 0 must be a number a double can hold exactly"},
        // Found by fuzzing: divisions beyond int's range were cast before they were checked.
        BadCase{"divisions = [4, 2]", "divisions = [411111111111111.0, 2]",
                "[mesh].generate.divisions: entries must be whole numbers in [1, 2000]"},
        // Haptics: further probes and the device's plane in a 3D body.
        BadCase{"grip_stiffness = 2000.0",
                "grip_stiffness = 2000.0\n[[haptics.probe]]\nwaypoints = [[0.1, 0.08]]\nduration = 1.0\n"
                "grip_stifness = 2000.0",
                "[[haptics.probe]] #1.grip_stifness: unknown key; did you mean 'grip_stiffness'?"},
        BadCase{"[haptics.hand]", "[[haptics.probe]]", "[haptics.hand] is missing"},
        BadCase{"waypoints = [[0.05, 0.08], [0.05, 0.04]]", "waypoints = [[0.05, 0.08], [0.05, 0.04, 0.0]]",
                "[haptics.hand].waypoints: entry 1 has 3 coordinates, entry 0 has 2"},
        BadCase{"waypoints = [[0.05, 0.08], [0.05, 0.04]]", "waypoints = [[0.05]]",
                "[haptics.hand].waypoints: entry 0 must be [x, y] (device) or [x, y, z]"},
        BadCase{"[haptics.hand]", "[haptics.plane]\norign = [0.0, 0.0, 0.0]\n[haptics.hand]",
                "[haptics.plane].orign: unknown key; did you mean 'origin'?"},
        BadCase{"[haptics.hand]", "[haptics.plane]\nx_axis = [0.0, 0.0, 0.0]\n[haptics.hand]",
                "[haptics.plane].x_axis: must be a non-zero direction"},
        BadCase{"[haptics.hand]", "[haptics.plane]\ny_axis = [1.0, 1.0, 0.0]\n[haptics.hand]",
                "[haptics.plane].y_axis: must be orthogonal to x_axis"},
        BadCase{"[haptics.hand]", "[haptics.plane]\norigin = [0.0, 0.0]\n[haptics.hand]",
                "[haptics.plane].origin: must have 3 entries, has 2"},
        // A point far off the body is a typo or the wrong units, not a request to snap to a corner.
        BadCase{"point = [0.2, 0.025]", "point = [3.0, 5.0]", "probe \"tip\".point is 5.68705 m from the mesh"},
        BadCase{"point = [0.2, 0.025]", "point = [3.0, 5.0]",
                "m from the mesh (nearest node 14 at [0.2, 0.05]); a point must lie within the longest edge (0.0559017 "
                "m) of a node"},
        BadCase{"total_force = [1.0, 0.0]",
                "total_force = [1.0, 0.0]\n[[load]]\npoint = [0.1, 0.3]\ntotal_force = [0.0, 1.0]",
                "load[1].point is 0.25 m from the mesh"},
        // A patch load must hold a facet, and is for loads only.
        BadCase{"group = \"right\"", "disc = { center = [0.2, 0.025], radius = 0.001 }",
                "load[0]: disc of radius 0.001 m holds no boundary facet centre"},
        BadCase{"group = \"right\"", "disc = { center = [0.2, 0.025], radius = -1.0 }", "[[load]] #1.disc.radius"},
        BadCase{"group = \"right\"", "disc = { centre = [0.2, 0.025], radius = 0.01 }",
                "disc.centre: unknown key; did you mean 'center'?"},
        BadCase{"group = \"left\"", "disc = { center = [0.0, 0.025], radius = 0.03 }", "[[fix]] #1"},
        BadCase{"divisions = [4, 2]", "divisions = [4, 2], mesher = \"cgal\", nodes = 100",
                "[mesh].generate.divisions: is for mesher = \"structured\"; a CGAL mesh takes nodes"},
        BadCase{"divisions = [4, 2]", "divisions = [4, 2], nodes = 100",
                "[mesh].generate.nodes: is for mesher = \"cgal\"; a structured mesh takes divisions"},
        BadCase{"divisions = [4, 2]", "mesher = \"cgal\", nodes = 2",
                "[mesh].generate.nodes: = 2: must be in [4, 500000]"},
        BadCase{"divisions = [4, 2]", "divisions = [4, 2], hole = 0.01",
                "[mesh].generate.hole: is for mesher = \"cgal\" (a structured mesh has no hole)"},
        BadCase{"divisions = [4, 2]", "mesher = \"cgal\", nodes = 100, hole = -0.01",
                "[mesh].generate.hole: = -0.01: must be > 0"},
        BadCase{"divisions = [4, 2]", "mesher = \"cgal\", nodes = 100, hole = 0.03",
                "[mesh].generate.hole: hole radius 0.03 m leaves less than a tenth of the shorter side (0.05 m) on "
                "each side: at most 0.02 m"},
        BadCase{"divisions = [4, 2]", "mesher = \"delaunay\"",
                "[mesh].generate.mesher: = \"delaunay\": must be one of structured cgal"},
        // Every further key with a range or a set of values (issue: keys without a bad case).
        BadCase{"thickness = 0.001", "thickness = 0.0", "[material].thickness: = 0: must be > 0"},
        BadCase{"retardation_time = ", "retardation_time = -1.0 #", "[material].retardation_time: = -1: must be >= 0"},
        BadCase{"mass_damping = ", "mass_damping = -2.0 #", "[material].mass_damping: = -2: must be >= 0"},
        BadCase{"young_modulus = 5.0e4", "young_modulus = 0.0", "[material].young_modulus: = 0: must be > 0"},
        BadCase{"size = [0.2, 0.05]", "size = [0.2, -0.05]", "[mesh].generate.size: entries must be > 0"},
        BadCase{"size = [0.2, 0.05]", "size = [0.2]", "[mesh].generate.size: must have 2 entries, has 1"},
        BadCase{"shape = \"rectangle\"", "shape = \"circle\"",
                "[mesh].generate.shape: = \"circle\": must be one of rectangle box"},
        BadCase{"[mesh]\n", "[mesh]\nfile = \"a.msh\"\n", "[mesh]: needs exactly one of file, generate"},
        BadCase{"[[fix]]\ngroup = \"left\"", "[[fix]]\nbox = [[0.0, 0.0], [-1.0, 1.0]]",
                "[[fix]] #1.box: min corner exceeds max corner"},
        BadCase{"[[fix]]\ngroup = \"left\"", "[[fix]]\nbox = [[0.0, 0.0]]",
                "[[fix]] #1.box: must be [[min...], [max...]]"},
        BadCase{"[[probe]]\nname = \"tip\"\npoint = [0.2, 0.025]", "[[probe]]\nname = \"tip\"\npoint = [0.2]",
                "[[probe]] #1.point: must have 2 to 3 entries, has 1"},
        BadCase{"total_force = [1.0, 0.0]", "total_force = [1.0, 0.0]\nstart = -1.0",
                "[[load]] #1.start: = -1: must be >= 0"},
        BadCase{"total_force = [1.0, 0.0]", "total_force = [1.0, 0.0]\nramp = -0.5",
                "[[load]] #1.ramp: = -0.5: must be >= 0"},
        BadCase{"[[probe]]", "[initial]\nvelocity = [1.0, 0.0, 0.0]\n[[probe]]",
                "[initial].velocity has 3 components; the mesh is 2D"},
        BadCase{"[[probe]]", "[initial]\nangular_velocity = [1.0, 0.0, 0.0]\n[[probe]]",
                "[initial].angular_velocity must be a number in 2D"},
        BadCase{"[[probe]]", "[initial]\nspin = 1.0\n[[probe]]", "[initial].spin: unknown key"},
        BadCase{"kind = \"filtered\"", "kind = \"filtered\"\nfilter = \"partial\"",
                "[solver].filter: = \"partial\": must be one of auto neighbors full"},
        BadCase{"kind = \"filtered\"", "kind = \"filtered\"\nsprings = \"hooke\"",
                "[solver].springs: = \"hooke\": must be one of auto lloyd van-gelder fitted"},
        BadCase{"kind = \"filtered\"", "kind = \"fem\"\nkinematics = \"large\"",
                "[solver].kinematics: = \"large\": must be one of linear nonlinear neo-hookean"},
        BadCase{"kind = \"filtered\"", "kind = \"filtered\"\nstrain_limit = -0.1",
                "[solver].strain_limit: = -0.1: must be >= 0"},
        BadCase{"kind = \"filtered\"", "kind = \"filtered\"\nmomentum_correction = 1",
                "[solver].momentum_correction: must be true or false"},
        BadCase{"kind = \"filtered\"", "kind = \"cvode\"\nrtol = 0.0", "[solver].rtol: = 0: must be > 0"},
        BadCase{"kind = \"filtered\"", "kind = \"cvode\"\natol = -1e-9", "[solver].atol: = -1e-09: must be > 0"},
        BadCase{"kind = \"filtered\"", "kind = \"fem\"\ndegree = 3", "[solver].degree: = 3: must be in [1, 2]"},
        BadCase{"kind = \"filtered\"", "kind = \"fem\"\nrefinements = -1",
                "[solver].refinements: = -1: must be in [0, 6]"},
        BadCase{"kind = \"filtered\"", "kind = \"fem\"\nscheme = \"rk4\"",
                "[solver].scheme: = \"rk4\": must be one of generalized-alpha newmark backward-euler"},
        BadCase{"max_force = 4.0", "max_force = 0.0", "[haptics].max_force: = 0: must be > 0"},
        BadCase{"max_force = 4.0", "max_force = 4.0\nrate = 0.0", "[haptics].rate: = 0: must be > 0"},
        BadCase{"max_force = 4.0", "max_force = 4.0\ncoupling_stiffness = -1.0",
                "[haptics].coupling_stiffness: = -1: must be > 0"},
        BadCase{"max_force = 4.0", "max_force = 4.0\ncoupling_damping = -1.0",
                "[haptics].coupling_damping: = -1: must be >= 0"},
        BadCase{"max_force = 4.0", "max_force = 4.0\ndevice = \"phantom\"",
                "[haptics].device: = \"phantom\": must be one of procat-sim replay"},
        BadCase{"grip_stiffness = 2000.0", "grip_stiffness = -5.0", "[haptics.hand].grip_stiffness: = -5: must be > 0"},
        BadCase{"duration = 1.0\ngrip", "duration = 0.0\ngrip", "[haptics.hand].duration: = 0: must be > 0"},
        BadCase{"[material]\n", "[materials]\n", "materials: unknown key; did you mean 'material'?"},
        BadCase{"[scene]\nname = \"plate\"\nduration = 1.0\noutput_interval = 0.01\n", "",
                "scene: missing (required table)"}),
    [](const auto& pinfo) { return "case" + std::to_string(pinfo.index); });

TEST(Scene, ReadSceneNamesAMissingFile) {
  try {
    read_scene("/nonexistent/scene.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.toml: cannot open scene file"), std::string::npos);
  }
}

TEST(Scene, EditDistanceSuggestsTheNearestKey) {
  EXPECT_EQ(edit_distance("youngs_modulus", "young_modulus"), 1u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
}

TEST(Scene, TractionIsLumpedByBoundaryLengthAndPointLoadIsNodal) {
  // A uniform traction on the right edge (2 segments of equal length): the end nodes carry
  // half the share of the middle ones, and the total is the requested force.
  const Model<2> m = test::model_from(kGood);
  ASSERT_EQ(m.loads.size(), 1u);
  const auto& l = m.loads[0];
  ASSERT_EQ(l.nodes.size(), 3u);
  EXPECT_NEAR(l.force.row(0).sum(), 1.0, 1e-14);
  EXPECT_NEAR(l.force(0, 0), 0.25, 1e-14);
  EXPECT_NEAR(l.force(0, 1), 0.5, 1e-14);
  const Model<2> p = test::model_from(with("group = \"right\"", "point = [0.2, 0.05]"));
  ASSERT_EQ(p.loads[0].nodes.size(), 1u);
  EXPECT_NEAR(p.loads[0].force(0, 0), 1.0, 1e-14);
}

/// A 16 x 4 plate clamped on its left, a disc load "tool" on its top edge around x = 0.1
/// (radius 0.02, total force (0.3, -1)) and a probe "under" that load.
Model<2> disc_on_plate() {
  return test::model_from(test::plate_scene(16, 4, R"(
[[fix]]
group = "left"
[[load]]
name = "tool"
disc = { center = [0.1, 0.05], radius = 0.02 }
total_force = [0.3, -1.0]
[[probe]]
name = "under"
load = "tool"
)"));
}

TEST(Scene, ADiscLoadIsAUniformTractionOnThePatchWithTheTotalForceAndItsMoment) {
  // A disc on the top edge of a 16 x 4 plate (segments of 0.0125 m) around x = 0.1 with radius
  // 0.02 holds the segments whose centres lie within 0.02 m: the four centred at 0.08125,
  // 0.09375, 0.10625 and 0.11875 (0.01875 and 0.00625 m away). A uniform traction lumped exactly on
  // linear facets gives nodal forces that sum to the total (to round-off) and whose moment
  // about the patch's centre (the facets' length-weighted centroid) is zero: the resultant
  // acts at the patch centre.
  const Model<2> m = disc_on_plate();
  ASSERT_EQ(m.loads.size(), 1u);
  const Load<2>& l = m.loads[0];
  ASSERT_FALSE(l.facets.empty());
  double length = 0;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& f : l.facets) {
    const double len = (m.mesh.points.col(f[1]) - m.mesh.points.col(f[0])).norm();
    length += len;
    centre += len * 0.5 * (m.mesh.points.col(f[0]) + m.mesh.points.col(f[1]));
    EXPECT_NEAR(m.mesh.points(1, f[0]), 0.05, 1e-12) << "a facet of the top edge";
  }
  centre /= length;
  EXPECT_NEAR(length, 0.05, 1e-12); // four segments of 0.0125
  const Eigen::Vector2d total = l.force.rowwise().sum();
  EXPECT_NEAR((total - Eigen::Vector2d(0.3, -1.0)).norm(), 0.0, 1e-14);
  double moment = 0;
  for (std::size_t k = 0; k < l.nodes.size(); ++k) {
    const Eigen::Vector2d r = m.mesh.points.col(l.nodes[k]) - centre;
    moment += r.x() * l.force(1, static_cast<Eigen::Index>(k)) - r.y() * l.force(0, static_cast<Eigen::Index>(k));
  }
  EXPECT_NEAR(moment, 0.0, 1e-15);
}

TEST(Scene, ALoadProbeRecordsTheDisplacementTheLoadWorksThrough) {
  // The disc of the test above: nodes at x = 0.075 ... 0.125 on the top edge carry 1/8, 1/4,
  // 1/4, 1/4, 1/8 of the force (four segments lumped on their ends). The probe's weights are
  // those shares, so for any field u the load's work sum_i f_i . u_i equals F . u_probe (the
  // forces are parallel), up to round-off.
  const Model<2> m = disc_on_plate();
  ASSERT_EQ(m.probes.size(), 1u);
  const auto& w = m.probe_weights.at(0);
  ASSERT_EQ(w.size(), 5u);
  double sum = 0;
  for (const auto& [node, share] : w) {
    const double x = m.mesh.points(0, node);
    EXPECT_NEAR(share, std::abs(x - 0.1) > 0.02 ? 0.125 : 0.25, 1e-14) << "node at x = " << x;
    sum += share;
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_NEAR(m.mesh.points(0, m.probes[0].second), 0.1, 1e-12) << "marked at the load's centre";
  EXPECT_EQ(m.probe_distance.at(0), 0.0);
  const Nodal<2> u = Nodal<2>::Random(2, m.num_nodes());
  const Load<2>& l = m.loads[0];
  double work = 0;
  for (std::size_t k = 0; k < l.nodes.size(); ++k)
    work += l.force.col(static_cast<Eigen::Index>(k)).dot(u.col(l.nodes[k]));
  EXPECT_NEAR(Eigen::Vector2d(0.3, -1.0).dot(m.probe_displacement(0, u)), work, 1e-14);
}

TEST(Scene, RampAndStepProfiles) {
  EXPECT_EQ(ramp_factor(0.5, 1.0, 0.0), 0.0);
  EXPECT_EQ(ramp_factor(1.0, 1.0, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(ramp_factor(1.25, 1.0, 0.5), 0.5);
  EXPECT_EQ(ramp_factor(2.0, 1.0, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(ramp_rate(1.25, 1.0, 0.5), 2.0);
  EXPECT_EQ(ramp_rate(2.0, 1.0, 0.5), 0.0);
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

#ifdef VTB_HAVE_CGAL_MESHERS
TEST(Scene, AnUnstructuredRectangleAndBoxComeFromCgal) {
  // mesher = "cgal": a rectangle with exactly the asked node count (mesh_polygon's contract),
  // covering [0, size] (the cells' areas sum to w h to round-off), with the structured
  // generator's group names; a box within 15 % of its count with its six faces as groups.
  const Scene r = parse_scene(
      "[scene]\nduration = 1.0\noutput_interval = 0.1\n[mesh]\n"
      "generate = { shape = \"rectangle\", size = [0.3, 0.1], mesher = \"cgal\", nodes = 200 }\n"
      "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = 1000.0\n[[fix]]\ngroup = \"left\"\n",
      "cgal.toml", ".");
  const Mesh2 m = std::get<Mesh2>(load_mesh(r));
  EXPECT_EQ(m.num_nodes(), 200);
  double area = 0;
  for (const auto& c : m.cells) area += signed_measure(m, c);
  EXPECT_NEAR(area, 0.03, 1e-15);
  for (const char* g : {"left", "right", "bottom", "top"}) EXPECT_GE(m.groups.at(g).nodes.size(), 3u) << g;
  EXPECT_NO_THROW(build_model<2>(r, m));
  const Scene b =
      parse_scene("[scene]\nduration = 1.0\noutput_interval = 0.1\n[mesh]\n"
                  "generate = { shape = \"box\", size = [0.1, 0.04, 0.03], mesher = \"cgal\", nodes = 300 }\n"
                  "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = 1000.0\n",
                  "cgal.toml", ".");
  const Mesh3 box = std::get<Mesh3>(load_mesh(b));
  EXPECT_NEAR(box.num_nodes(), 300, 45);
  double volume = 0;
  for (const auto& c : box.cells) volume += signed_measure(box, c);
  EXPECT_NEAR(volume, 0.1 * 0.04 * 0.03, 1e-12 * 0.1 * 0.04 * 0.03);
  for (const char* g : {"left", "right", "bottom", "top", "front", "back"})
    EXPECT_GE(box.groups.at(g).nodes.size(), 3u) << g;
}

/// A scene on the example bean (meshes/data/bean.off) with the given [mesh] generate's extra keys.
std::string bean_scene(const std::string& keys) {
  return "[scene]\nduration = 0.01\noutput_interval = 0.01\n[mesh]\n"
         "generate = { shape = \"surface\", file = \"bean.off\"" +
         keys +
         " }\n[material]\nyoung_modulus = 2.0e4\npoisson_ratio = 0.4\ndensity = 1000.0\n"
         "[[fix]]\nbox = [[-0.04, -0.02, 0.0], [0.04, 0.03, 0.0041]]\n[[load]]\n"
         "disc = { center = [0.0, 0.008, 0.024], radius = 0.004 }\ntotal_force = [0.0, 0.0, -0.05]\n";
}

TEST(Scene, ASurfaceIsMeshedFromTheScenesFolderAndGradedWhereAsked) {
  const std::filesystem::path data = std::filesystem::path(VTB_SOURCE_DIR) / "meshes" / "data";
  const Scene s = parse_scene(bean_scene(", nodes = 600"), "bean.toml", data);
  EXPECT_EQ(s.mesh.file, data / "bean.off") << "the file is relative to the scene's folder";
  const Mesh3 m = std::get<Mesh3>(load_mesh(s));
  EXPECT_NEAR(m.num_nodes(), 600, 0.15 * 600);
  EXPECT_GT(m.groups.at("surface").facets.size(), 100u);
  EXPECT_NO_THROW(build_model<3>(s, m)) << "the fix box and the disc find the flat underside and the top";
  const Scene g = parse_scene(bean_scene(", cell_size = 0.006, refine = [{ center = [0.0, 0.008, 0.024], "
                                         "radius = 0.004, size = 0.0015 }]"),
                              "bean.toml", data);
  ASSERT_EQ(g.mesh.refine.size(), 1u);
  EXPECT_EQ(g.mesh.refine[0].size, 0.0015);
  EXPECT_EQ(g.mesh.refine[0].growth, kRefineGrowth) << "the default growth";
  const Mesh3 graded = std::get<Mesh3>(load_mesh(g));
  const Mesh3 coarse = std::get<Mesh3>(load_mesh(parse_scene(bean_scene(", cell_size = 0.006"), "bean.toml", data)));
  EXPECT_GT(graded.num_nodes(), coarse.num_nodes()) << "the refinement adds nodes under the load";
  const std::vector<std::pair<std::string, std::string>> bad{
      {", nodes = 600, cell_size = 0.004", "needs exactly one of nodes, cell_size"},
      {"", "needs exactly one of nodes, cell_size"},
      {", nodes = 600, size = [0.1, 0.1, 0.1]", "[mesh].generate.size: is not for shape = \"surface\""},
      {", nodes = 600, mesher = \"structured\"", "must be one of cgal"},
      {", nodes = 600, scale = 0.0", "[mesh].generate.scale: = 0: must be > 0"},
      {", nodes = 600, refine = { center = [0.0, 0.0], radius = 0.01, size = 0.001 }", "refine[0].center"},
      {", nodes = 600, refine = { center = [0.0, 0.0, 0.0], radius = 0.01, size = 0.0 }", "refine[0].size"},
      {", nodes = 600, refine = { center = [0.0, 0.0, 0.0], radius = 0.01, size = 0.001, growth = 2.0 }",
       "refine[0].growth: = 2: must be in (0, 1]"},
      {", nodes = 600, refine = { centre = [0.0, 0.0, 0.0], radius = 0.01, size = 0.001 }", "did you mean 'center'"},
      {", nodes = 600, refine = 3", "[mesh].generate.refine"}};
  for (const auto& [keys, expect] : bad) {
    try {
      load_mesh(parse_scene(bean_scene(keys), "bean.toml", data));
      ADD_FAILURE() << keys << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << keys << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find("bean.toml"), std::string::npos) << e.what();
    }
  }
  // A broken surface: the scene file, the key and the surface's own one line.
  const test::FreshDir dir;
  std::ofstream(dir / "bean.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  try {
    load_mesh(parse_scene(bean_scene(", nodes = 600"), "bean.toml", dir.path()));
    ADD_FAILURE() << "an open surface was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("[mesh].generate: " + (dir / "bean.off").string() + ": not closed"),
              std::string::npos)
        << e.what();
  }
}
#endif

} // namespace
} // namespace vtb
