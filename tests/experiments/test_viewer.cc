// The viewer, headless under Xvfb (ctest runs this program through xvfb-run): its pictures are
// checked for content, not for pixels: the body is drawn where the scene puts it, a drag pulls
// it toward the cursor and brings out the strain colours, and an unstable solver is reported
// while the viewer carries on.
#include "../../experiments/viewer/viewer.hh"
#include "support/fresh_dir.hh"
#include "support/small_models.hh"
#include "vtb/base/input_error.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/stepper/live_sim.hh"

#include <gtest/gtest.h>

#include <array>
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace vtb {
namespace {

/// An RGB image as loaded from a PNG.
struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> px;
  const unsigned char* at(int x, int y) const { return &px[(static_cast<std::size_t>(y) * w + x) * 3]; }
};

Image load(const std::filesystem::path& file) {
  Image im;
  int n = 0;
  unsigned char* data = stbi_load(file.c_str(), &im.w, &im.h, &n, 3);
  if (!data) throw std::runtime_error("cannot read " + file.string());
  im.px.assign(data, data + static_cast<std::size_t>(im.w) * im.h * 3);
  stbi_image_free(data);
  return im;
}

// The drawing area lies between the panel (330 px) and the colour bar (150 px) of a 1280 x 760
// window; the background is (0.93, 0.94, 0.96).
constexpr int kLeft = 340, kRight = 1280 - 160;
bool background(const unsigned char* p) {
  return std::abs(p[0] - 237) <= 3 && std::abs(p[1] - 240) <= 3 && std::abs(p[2] - 245) <= 3;
}
/// Body pixels: viridis colours, i.e. neither background, nor the (dark) mesh lines and
/// labels, nor the white overlays (handle, pulls).
bool body(const unsigned char* p) {
  // Every viridis colour is far from grey (its channels spread by 80 or more); lines, text
  // and the white overlays, anti-aliased or not, are grey.
  const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
  return !background(p) && hi - lo > 40;
}
/// The warm end of viridis (green to yellow): strain above about half the scale.
bool warm(const unsigned char* p) {
  return p[1] > 140 && p[2] < 140;
}

struct Box {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  long count = 0;
};
Box body_box(const Image& im) {
  Box b;
  for (int y = 0; y < im.h; ++y)
    for (int x = kLeft; x < kRight; ++x)
      if (body(im.at(x, y))) {
        b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x), b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
        ++b.count;
      }
  return b;
}
long count_if(const Image& im, bool (*pred)(const unsigned char*)) {
  long n = 0;
  for (int y = 0; y < im.h; ++y)
    for (int x = kLeft; x < kRight; ++x) n += pred(im.at(x, y));
  return n;
}

/// A 0.2 x 0.05 plate clamped on the left with a probe at its right end, nothing loading it
/// but what `more` adds (scene tables).
Scene plate(const std::string& more = "") {
  return parse_scene(test::plate_scene(16, 4, more + R"(
[[fix]]
group = "left"
[[probe]]
name = "tip"
point = [0.2, 0.025]
[solver]
kind = "filtered"
dt = 1e-3
)",
                                       0.02),
                     "plate.toml", ".");
}

Image shot(const Scene& s, viewer::ViewOptions o, const test::FreshDir& dir, const std::string& name,
           std::string* out = nullptr) {
  o.screenshot = (dir / name).string();
  ::testing::internal::CaptureStdout();
  const int code = viewer::run_viewer(s, o);
  const std::string text = ::testing::internal::GetCapturedStdout();
  if (out) *out = text;
  EXPECT_EQ(code, 0) << text;
  EXPECT_FALSE(std::filesystem::exists(dir / (name + ".part")));
  return load(dir / name);
}

TEST(Viewer, AtRestThePlateIsDrawnWhereTheSceneIsWithItsMarkers) {
  const test::FreshDir dir;
  viewer::ViewOptions o;
  o.frames = 5;
  const Image im = shot(plate(), o, dir, "rest.png");
  ASSERT_EQ(im.w, 1280);
  const Box b = body_box(im);
  // Not blank: the plate covers a good part of the drawing area (it is framed to about 3/4
  // of the area's width).
  ASSERT_GT(b.count, 20000) << "the body is drawn";
  // Its shape: 0.2 x 0.05 at rest, so a 4:1 box (within two pixels' worth at each end).
  const double aspect = static_cast<double>(b.x1 - b.x0 + 1) / (b.y1 - b.y0 + 1);
  EXPECT_NEAR(aspect, 4.0, 0.15) << b.x0 << " " << b.x1 << " " << b.y0 << " " << b.y1;
  // Centred in the drawing area (the camera frames the rest shape's box).
  EXPECT_NEAR(0.5 * (b.x0 + b.x1), 0.5 * (330 + 1280 - 150), 4);
  EXPECT_NEAR(0.5 * (b.y0 + b.y1), 380, 4);
  // The clamp's markers (blue) on the left edge, the probe (red) on the right.
  long blue_left = 0, red_right = 0;
  for (int y = b.y0 - 4; y <= b.y1 + 4; ++y)
    for (int x = kLeft; x < kRight; ++x) {
      const unsigned char* p = im.at(x, y);
      if (p[2] > 200 && p[0] < 90 && std::abs(x - b.x0) < 6) ++blue_left;
      if (p[0] > 200 && p[1] < 100 && p[2] < 100 && std::abs(x - b.x1) < 6) ++red_right;
    }
  EXPECT_GT(blue_left, 10);
  EXPECT_GT(red_right, 4);
}

TEST(Viewer, ADragPullsThePlateTowardTheCursorAndShowsStrain) {
  const test::FreshDir dir;
  viewer::ViewOptions o;
  o.frames = 60;
  const Image rest = shot(plate(), o, dir, "rest.png");
  o.drag = viewer::parse_drag("0.15,0.05:0.15,0.08");
  std::string text;
  const Image pulled = shot(plate(), o, dir, "pulled.png", &text);
  EXPECT_NE(text.find("pulls 1 ("), std::string::npos) << text;
  // The top edge rises at the pulled column, and much less near the clamp: the plate is
  // pulled toward the cursor, not moved as a whole.
  const Box b = body_box(rest);
  auto rise = [&](int column) {
    auto top = [&](const Image& im) {
      for (int y = 0; y < im.h; ++y)
        if (body(im.at(column, y))) return y;
      return im.h;
    };
    return top(rest) - top(pulled);
  };
  const int pulled_column = b.x0 + static_cast<int>(0.75 * (b.x1 - b.x0));
  const int clamp_column = b.x0 + static_cast<int>(0.1 * (b.x1 - b.x0));
  EXPECT_GT(rise(pulled_column), 10) << "pulled up by more than 10 px";
  EXPECT_LT(rise(clamp_column), 0.5 * rise(pulled_column));
  // At rest the colour scale has nothing to show (uniform dark); pulled, warm colours appear.
  EXPECT_LT(count_if(rest, warm), 50);
  EXPECT_GT(count_if(pulled, warm), 500);
}

TEST(Viewer, ThePanelRunsTheTensorFilterOnFittedSprings) {
  // The panel's choices rebuild the simulation: the lag-free tensor filter on springs fitted
  // to the FEM. A pull then moves the plate and the run stays sound; the calibration is the
  // one chosen, and a calibration name the panel does not offer is refused with the old kept.
  const test::FreshDir cache; // the fit's cache, away from the user's
  ::setenv("VTB_CACHE_DIR", cache.path().c_str(), 1);
  const Scene scene = plate();
  LiveSim<2> sim(scene, std::get<Mesh2>(load_mesh(scene)), SimControls{});
  SimControls c = sim.controls();
  c.filter = solvers::kFilterTensor;
  c.springs = "fitted";
  sim.configure(c);
  EXPECT_EQ(sim.model().net.calibration, "fitted");
  const int tip = sim.model().probes.front().second;
  sim.add_pull(tip, sim.position(tip) + Vec<2>(0.0, 0.01), true);
  for (int k = 0; k < 20; ++k) sim.advance(0.01, 10.0);
  EXPECT_TRUE(sim.failure().empty()) << sim.failure();
  EXPECT_GT(sim.state().u.col(tip)(1), 1e-4);
  SimControls bad = sim.controls();
  bad.springs = "hooke";
  EXPECT_THROW(sim.configure(bad), InputError);
  EXPECT_EQ(sim.controls().springs, "fitted");
  ::unsetenv("VTB_CACHE_DIR");
}

/// A pull 4 mm upward at the top face's centre of a 2 cm box (2.5 mm spacing, Lloyd's springs,
/// bottom clamped) for 0.2 s with the viewer's pull spring, with the scene's grab radius.
/// Returns the pull, the largest spring strain and the pull's force.
Pull<3> held_pull(double radius, double& max_strain, double& force) {
  const std::string text = "[scene]\nname = \"grab\"\nduration = 1.0\noutput_interval = 0.01\n[mesh]\n"
                           "generate = { shape = \"box\", size = [0.02, 0.02, 0.02], divisions = [8, 8, 8] }\n"
                           "[material]\nyoung_modulus = 5.0e3\npoisson_ratio = 0.45\ndensity = 1000.0\n"
                           "retardation_time = 0.05\n[[fix]]\ngroup = \"bottom\"\n[solver]\ndt = 1.0e-3\n"
                           "springs = \"lloyd\"\n[haptics]\ntip_radius = " +
                           std::to_string(radius) + "\n";
  const Scene scene = parse_scene(text, "grab.toml", ".");
  // The scene's springs (Lloyd's), as `vtb view` starts (initial_controls): default controls
  // would ask for "auto", whose fit this small box's pull is not about.
  SimControls controls;
  controls.springs = scene.solver.springs;
  LiveSim<3> sim(scene, std::get<Mesh3>(load_mesh(scene)), controls);
  int top = 0;
  const Vec<3> centre(0.01, 0.01, 0.02);
  for (int i = 0; i < sim.model().num_nodes(); ++i)
    if ((sim.position(i) - centre).norm() < (sim.position(top) - centre).norm()) top = i;
  sim.add_pull(top, sim.position(top) + Vec<3>(0.0, 0.0, 0.004), true);
  for (int k = 0; k < 20; ++k) sim.advance(0.01, 10.0);
  EXPECT_TRUE(sim.failure().empty()) << sim.failure();
  max_strain = sim.stats().max_strain;
  force = sim.pull_force(0).norm();
  return sim.pull(0);
}

TEST(Viewer, APullGrabsAPatchOfTheToolsSizeNotANode) {
  // A pull holds the boundary nodes within the scene's tip radius (4 mm by default in 3D) at
  // rest (the nearest 16 at most), equally weighted, one spring on their mean: the patch rises
  // as a bulge where one node was drawn out into a spike (a 2,448-node tissue block: max spring
  // strain 3.37). On this box's 2.5 mm grid a 4 mm patch holds the centre, its four neighbours
  // and the four diagonal ones. The patch holds more tissue, so the same pull spring
  // moves it less and pulls harder; and yet its largest spring strain is well below the single
  // node's (measured 0.16 at 0.14 N against 0.32 at 0.094 N).
  double patch_strain = 0, node_strain = 0, patch_force = 0, node_force = 0;
  const Pull<3> patch = held_pull(0.004, patch_strain, patch_force);
  const Pull<3> node = held_pull(0.0, node_strain, node_force);
  EXPECT_EQ(node.count, 1);
  EXPECT_EQ(patch.count, 9);
  EXPECT_NEAR(patch.weights[0] * patch.count, 1.0, 1e-12);
  EXPECT_GT(patch_force, node_force);
  EXPECT_LT(patch_strain, 0.7 * node_strain) << patch_strain << " against " << node_strain;
}

TEST(Viewer, ThePanelSaysWhatTheAutoFilterRuns) {
  // With no filter chosen (auto) the panel names the filter auto resolved to for this model:
  // the lag-free tensor filter on the 2D plate (chosen_filter). A filter picked by name runs as
  // named, and a solver that is not the filtered one runs no filter.
  const test::FreshDir cache;
  ::setenv("VTB_CACHE_DIR", cache.path().c_str(), 1);
  const Scene scene = plate();
  LiveSim<2> sim(scene, std::get<Mesh2>(load_mesh(scene)), SimControls{});
  EXPECT_EQ(sim.controls().filter, solvers::kFilterAuto);
  EXPECT_EQ(sim.running_filter(), chosen_filter(sim.model(), solvers::kFilterAuto));
  EXPECT_EQ(sim.running_filter(), solvers::kFilterTensor);
  SimControls c = sim.controls();
  c.filter = solvers::kFilterFull;
  sim.configure(c);
  EXPECT_EQ(sim.running_filter(), solvers::kFilterFull);
  c.solver = solvers::kImplicitEuler;
  sim.configure(c);
  EXPECT_TRUE(sim.running_filter().empty());
  ::unsetenv("VTB_CACHE_DIR");
}

TEST(Viewer, KeepsTheSpringsLoadErrorUntilTheSpringsChange) {
  // The panel's stiffness, dt and filter rebuild the model but not the springs' error on the
  // scene's loads: both linear answers scale as 1 / E, so their relative difference does not
  // change, and the viewer keeps the value (measuring it took about 2 s at 10k nodes). Other
  // springs are measured again. To round-off: each static answer comes from a sparse direct
  // solve whose relative error is about cond(K) eps (K's condition on this 16 x 4 plate is of
  // order (16 x 4)^2 / 4 ~ 1e3, eps = 1.1e-16: ~1e-13); the error is the difference of two
  // such answers over one of them, so its round-off is that 1e-13 absolute, not relative to an
  // error of 0.005 (which would ask 5e-15 of a difference of two 1e-13-accurate fields).
  const test::FreshDir cache;
  ::setenv("VTB_CACHE_DIR", cache.path().c_str(), 1);
  const Scene scene = plate("[[load]]\ngroup = \"right\"\ntotal_force = [0.0, -0.5]\n");
  LiveSim<2> sim(scene, std::get<Mesh2>(load_mesh(scene)), SimControls{});
  const double first = sim.model().net.calibration_load_error;
  ASSERT_TRUE(std::isfinite(first));
  SimControls c = sim.controls();
  c.stiffness_scale = 3.0;
  c.dt = 4e-3;
  c.filter = solvers::kFilterFull;
  sim.configure(c);
  EXPECT_EQ(sim.model().net.calibration_load_error, first); // kept, not measured again
  MaterialDesc stiffer = scene.material;
  stiffer.young_modulus *= 3.0;
  constexpr double kRoundOff = 1e-13; // absolute, on a relative error (above)
  EXPECT_NEAR(static_load_error<2>(sim.model(), sim.model().net, stiffer), first, kRoundOff);
  c.springs = "lloyd";
  sim.configure(c);
  const double lloyd = sim.model().net.calibration_load_error;
  EXPECT_NEAR(lloyd, static_load_error<2>(sim.model(), sim.model().net, stiffer), kRoundOff);
  EXPECT_GT(std::abs(lloyd - first), 1e-3) << "Lloyd's springs and the fitted ones differ on this plate";
  ::unsetenv("VTB_CACHE_DIR");
}

TEST(Viewer, AnUnstableSolverIsReportedAndTheViewerCarriesOn) {
  // The explicit scheme at 1 ms, far beyond its limit on this plate (~1e-6 s): it diverges
  // within a few steps; the viewer reports which solver and when, keeps drawing, and exits 0.
  const test::FreshDir dir;
  viewer::ViewOptions o;
  o.frames = 10;
  o.solver = "explicit";
  o.dt = 1e-3;
  o.drag = viewer::parse_drag("0.15,0.05:0.15,0.08");
  std::string text;
  const Image im = shot(plate(), o, dir, "unstable.png", &text);
  EXPECT_NE(text.find("vtb view: unstable: explicit went unstable at t = "), std::string::npos) << text;
  EXPECT_GT(count_if(im, background), 100000) << "the window still draws";
}

/// |F| of the viewer's device line ("vtb view: device: ... |F| = X N ..."); NaN without one.
double device_force(const std::string& text) {
  const auto at = text.find("vtb view: device: ");
  double force = std::nan("");
  if (at == std::string::npos || std::sscanf(text.c_str() + text.find("|F| = ", at), "|F| = %lf", &force) != 1)
    ADD_FAILURE() << "no device line in: " << text;
  return force;
}

/// A scripted device session's options: 90 frames (1.5 s), device mode, the hand along `drag`
/// over the first half and held (ViewOptions::drag).
viewer::ViewOptions device_press(const char* drag) {
  viewer::ViewOptions o;
  o.frames = 90;
  o.device = true;
  o.drag = viewer::parse_drag(drag);
  return o;
}

TEST(Viewer, DeviceModePressesTheSurfaceThroughTheProcatWithinItsLimit) {
  // The paper's interaction: the hand (the scripted drag) moves the ProCAT's handle 5 mm into
  // the top edge of the press scene's plate and holds. The proxy stays on the top edge, the
  // device feels a push within its limit (the session's lockstep run feels ~0.09 N here),
  // and the edge under the handle is pushed down in the picture.
  const test::FreshDir dir;
  const Scene press = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_press.toml");
  viewer::ViewOptions o;
  o.frames = 90;
  const Image rest = shot(press, o, dir, "rest.png");
  o.device = true;
  o.drag = viewer::parse_drag("0.05,0.08:0.05,0.045");
  std::string text;
  const Image pressed = shot(press, o, dir, "press.png", &text);
  const double force = device_force(text);
  EXPECT_GT(force, 0.03);
  EXPECT_LT(force, 4.0);
  EXPECT_NE(text.find("saturated 0, in contact"), std::string::npos) << text;
  const Box b = body_box(rest);
  const int column = b.x0 + static_cast<int>(0.25 * (b.x1 - b.x0)); // x = 0.05 of 0.2
  auto top = [&](const Image& im) {
    for (int y = b.y0 - 20; y < b.y1; ++y)
      if (body(im.at(column, y))) return y;
    return b.y1;
  };
  EXPECT_GT(top(pressed), top(rest) + 3) << "the edge under the handle is pushed down";
}

TEST(Viewer, DeviceModeDrivesAPlugInLoadedAtRunTime) {
  // `--device=plugin:PATH`: the example driver of experiments/devices (its "hardware" moves the
  // handle on a straight press, the drag's of the test above, over 0.75 s, and holds) is the
  // device; the mouse moves nothing. Same press, same coupling: the held force is the simulated
  // ProCAT's within the difference of a handle held rigidly against one held through a grip
  // spring (a few %: the grip is 2,000 N/m against the coupling's 400 N/m on a soft plate),
  // so a bound of 25 % says it is the same press, not a different one. Every tick's command
  // reaches the driver (its log, written at close), none above its 3 N limit, none non-finite.
  const test::FreshDir dir;
  Scene press = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_press.toml");
  viewer::ViewOptions o = device_press("0.05,0.08:0.05,0.045");
  std::string sim_text;
  shot(press, o, dir, "sim.png", &sim_text);
  const double simulated = device_force(sim_text);
  const std::filesystem::path log = dir / "driver.log";
  press.haptics->plugin_config = "from=0.05,0.08 to=0.05,0.045 seconds=0.75 log=" + log.string();
  o.drag.reset();
  o.driver = std::string("plugin:") + VTB_EXAMPLE_DEVICE_PLUGIN;
  std::string text;
  shot(press, o, dir, "driver.png", &text);
  EXPECT_NE(text.find("vtb view: device: example-press, "), std::string::npos) << text;
  const double force = device_force(text);
  EXPECT_NE(text.find("saturated 0, in contact"), std::string::npos) << text;
  EXPECT_NEAR(force, simulated, 0.25 * simulated) << text;
  long ticks = 0, commands = -1, nonfinite = -1;
  double max_force = -1, max_stiffness = -1;
  ASSERT_EQ(std::sscanf(text.c_str() + text.find("vtb view: device: example-press, "),
                        "vtb view: device: example-press, %ld servo ticks", &ticks),
            1);
  std::ifstream in(log);
  std::string line;
  ASSERT_TRUE(std::getline(in, line)) << "the driver's log at close: " << log;
  ASSERT_EQ(std::sscanf(line.c_str(), "commands %ld max_force %lf nonfinite %ld max_stiffness %lf", &commands,
                        &max_force, &nonfinite, &max_stiffness),
            4)
      << line;
  EXPECT_GE(commands, ticks) << "every tick commands the driver (and 0 N at close)";
  EXPECT_LE(max_force, 3.0) << "the driver's own limit";
  EXPECT_GE(max_force, force);
  EXPECT_EQ(nonfinite, 0);
}

TEST(Viewer, DeviceModeRefusesADriverItCannotOpenInOneLine) {
  // A driver the viewer does not take, or a library that is not there: one line naming it.
  const Scene press = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_press.toml");
  const test::FreshDir dir;
  viewer::ViewOptions o;
  o.frames = 2;
  o.device = true;
  for (const std::string driver : {"udp:127.0.0.1:9000", "plugin:/nonexistent/libdriver.so"}) {
    o.driver = driver;
    o.screenshot = (dir / "x.png").string();
    try {
      viewer::run_viewer(press, o);
      ADD_FAILURE() << driver << " was taken";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find(driver.substr(driver.find(':') + 1)), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png")) << "nothing written";
  }
}

/// How many pixels of the drawing area differ between two pictures of the same size.
long differing(const Image& a, const Image& b) {
  long n = 0;
  for (int y = 0; y < a.h; ++y)
    for (int x = kLeft; x < kRight; ++x)
      n += std::abs(a.at(x, y)[0] - b.at(x, y)[0]) + std::abs(a.at(x, y)[1] - b.at(x, y)[1]) +
               std::abs(a.at(x, y)[2] - b.at(x, y)[2]) >
           30;
  return n;
}

TEST(Viewer, DeviceModeIn3DPressesTheSlabInTheScenesPlane) {
  // The 3D haptic scene: the ProCAT acts in the slab's [haptics.plane] (the x-z plane through
  // y = 0.025). The hand (the scripted drag, as world points) moves from 3 cm above the top face
  // (z = 0.02) to 5 mm into it and holds. The proxy rests on the deformed surface (the AABB
  // tree's contact), the device feels a push within its limit (the coupling is 400 N/m, so at
  // most 2 N for a 5 mm gap; the soft layer gives, so less, and more than the 2D test's floor),
  // and the picture changes where the handle presses: the handle, its path and the force arrow.
  const test::FreshDir dir;
  const Scene slab = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_slab_press.toml");
  viewer::ViewOptions o;
  o.frames = 90;
  const Image rest = shot(slab, o, dir, "rest.png");
  o.device = true;
  o.drag = viewer::parse_drag("0.1,0.025,0.05:0.1,0.025,0.015");
  std::string text;
  const Image pressed = shot(slab, o, dir, "press.png", &text);
  const double force = device_force(text);
  EXPECT_GT(force, 0.03) << text;
  EXPECT_LT(force, 2.0) << text;
  EXPECT_NE(text.find("saturated 0, in contact"), std::string::npos) << text;
  EXPECT_EQ(text.find("unstable"), std::string::npos) << text;
  EXPECT_GT(differing(rest, pressed), 400) << "the handle, its path and the force arrow are drawn";
}

TEST(Viewer, DeviceModeOnALargeBodyStepsItAtTheRateItAffords) {
  // The slab press on a 10,829-node slab (structured 48 x 12 x 16, Lloyd's springs): its step
  // costs more than half a servo period, so device mode steps it at the rate it affords, as
  // `vtb haptics` does (docs/haptics.md), each step's servo ticks solving the contact against
  // the local model of the step before. Headless frames are 1/60 s of simulated time, so what
  // is checked is the choice and the press, not the pace: a step of several servo periods, and
  // the held press rendered in contact within the device's limit (0.89 N in the session's real
  // time on the 10k CGAL slab; the coupling's 400 N/m over the 5 mm gap bounds it by 2 N).
  const test::FreshDir dir;
  Scene slab = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_slab_press.toml");
  slab.solver.springs = "lloyd";
  slab.mesh = MeshDesc{};
  slab.mesh.shape = "box";
  slab.mesh.size = Eigen::VectorXd::Map(std::array<double, 3>{0.2, 0.05, 0.02}.data(), 3);
  Eigen::VectorXi divisions(3);
  divisions << 48, 12, 16;
  slab.mesh.divisions = divisions;
  viewer::ViewOptions o = device_press("0.1,0.025,0.05:0.1,0.025,0.015");
  std::string text;
  shot(slab, o, dir, "large.png", &text);
  double dt = 0;
  const auto at = text.find("dt = ");
  ASSERT_NE(at, std::string::npos) << text;
  ASSERT_EQ(std::sscanf(text.c_str() + at, "dt = %lf", &dt), 1) << text;
  EXPECT_GT(dt, 0.0015) << "the physics steps every few servo periods: " << text;
  const double force = device_force(text);
  EXPECT_GT(force, 0.3) << text;
  EXPECT_LT(force, 2.0) << text;
  EXPECT_NE(text.find("saturated 0, in contact"), std::string::npos) << text;
  EXPECT_EQ(text.find("unstable"), std::string::npos) << text;
}

/// Pixels of the tool tip's colour (200, 30, 30: its outline and its footprint's dots).
int tip_pixels(const Image& im) {
  int n = 0;
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x) {
      const unsigned char* p = im.at(x, y);
      n += std::abs(p[0] - 200) < 30 && p[1] < 70 && p[2] < 70;
    }
  return n;
}

TEST(Viewer, DeviceModeDrawsTheToolTipAndItsFootprint) {
  // The slab press with its 4 mm tip: the viewer draws the tip's outline in its face's plane
  // at the proxy and the footprint's nodes (docs/haptics.md); with a point proxy (tip_radius =
  // 0) neither is drawn. The tip's colour is kept out of the strain colour map (viridis has no
  // strong red), so the count separates them: measured 156 against 1 pixel.
  const test::FreshDir dir;
  Scene slab = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_slab_press.toml");
  viewer::ViewOptions o = device_press("0.1,0.025,0.05:0.1,0.025,0.015");
  const Image tipped = shot(slab, o, dir, "tip.png");
  slab.haptics->tip_radius = 0.0;
  const Image point = shot(slab, o, dir, "point.png");
  EXPECT_GT(tip_pixels(tipped), 100);
  EXPECT_LT(tip_pixels(point), 10);
}

TEST(Viewer, A3DBodyAtRestIsShadedSoItsShapeReads) {
  // At rest every cell has zero strain: one colour (viridis' dark end) on every face, so only
  // the light tells the faces apart. The slab's visible faces must differ in brightness by
  // more than 30 of 255 between the darker and the brighter tenth of its pixels: a flat colour
  // gives 0, the earlier fixed light gave about 6 on that dark colour.
  const test::FreshDir dir;
  const Scene slab = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/slab_press.toml");
  viewer::ViewOptions o;
  o.frames = 2;
  const Image im = shot(slab, o, dir, "slab.png");
  std::vector<double> luma;
  for (int y = 0; y < im.h; ++y)
    for (int x = kLeft; x < kRight; ++x) {
      const unsigned char* p = im.at(x, y);
      const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
      if (!background(p) && hi - lo > 20) luma.push_back(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]);
    }
  ASSERT_GT(luma.size(), 20000u) << "the body is drawn";
  std::sort(luma.begin(), luma.end());
  const double p10 = luma[luma.size() / 10], p90 = luma[luma.size() * 9 / 10];
  EXPECT_GT(p90 - p10, 30.0) << "p10 " << p10 << ", p90 " << p90;
}

TEST(Viewer, BadOptionsAreInputErrors) {
  EXPECT_THROW(viewer::parse_drag("0.1,0.2"), InputError);
  EXPECT_THROW(viewer::parse_drag("0.1,x:0.2,0.3"), InputError);
  viewer::ViewOptions o;
  o.frames = 1;
  o.solver = "cvode";
  EXPECT_THROW(viewer::run_viewer(plate(), o), InputError) << "cvode does not run interactively";
  o.solver.reset();
  o.frames = 0;
  o.screenshot = "x.png";
  EXPECT_THROW(viewer::run_viewer(plate(), o), InputError) << "a screenshot needs --frames";
  o.screenshot.clear();
  o.frames = 1;
  o.drag = viewer::parse_drag("700,0:700.1,0"); // 700 m from a 0.2 m plate: not a pull on it
  EXPECT_THROW(viewer::run_viewer(plate(), o), InputError) << "a pull must start on the body";
}

} // namespace
} // namespace vtb
