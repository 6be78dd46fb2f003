#pragma once
/// \file
/// `vtb view SCENE`: the paper's interactive system (docs/viewer.md). A GLFW window with an
/// OpenGL 3.3 core view of the body coloured by strain, and a Dear ImGui panel that switches
/// solver, filter, dt and stiffness live; left drag pulls the body through a virtual coupling.
/// With `frames` > 0 it renders that many frames at a fixed 1/60 s of simulated time each
/// (deterministic), holds the scripted drag from the first frame, writes the last frame as a
/// PNG and exits: the mode that tests and figures use under xvfb-run.

#include "vtb/problem/scene.hh"
#include "vtb/springs/load_check.hh"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <utility>

namespace vtb::viewer {

struct ViewOptions {
  int frames = 0;                                                  ///< 0: interactive until the window closes
  std::string screenshot;                                          ///< PNG of the last frame (with frames > 0)
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> drag; ///< scene points: grab at first, pull to second
  std::optional<std::string> solver, filter;
  std::optional<double> dt;
  bool device =
      false; ///< device mode: the mouse (or the drag) is the hand on the simulated ProCAT (3D: in [haptics.plane])
  std::string driver; ///< device mode's device: "" or "procat-sim", or "plugin:PATH" (a driver moves the handle)
  int width = 1280, height = 760;
  Yardstick yardstick; ///< what the panel's load check measures the springs against (empty: P1 on the mesh)
};

/// "X0,Y0:X1,Y1" (or with Z in 3D) -> the two points; InputError naming --drag otherwise.
std::pair<Eigen::Vector3d, Eigen::Vector3d> parse_drag(const std::string& text);

/// No display, no OpenGL 3.3 context: the one line says so (exit code 3 in the CLI).
struct NoDisplay : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs the viewer; returns the exit code (0). Throws InputError for a bad scene or option,
/// NoDisplay when no window can be opened.
int run_viewer(const Scene& scene, const ViewOptions& options);

} // namespace vtb::viewer
