#pragma once
/// \file
/// One viewer session over a body of dimension dim: the window's frame (physics substeps,
/// scene drawing, the panel and its overlays) and the mouse. Internal to experiments/viewer.

#include "camera.hh"
#include "device_mode.hh"
#include "gl_draw.hh"
#include "surface.hh"
#include "viewer.hh"
#include "vtb/stepper/live_sim.hh"

struct ImDrawList;

#include <array>
#include <memory>
#include <vector>

struct GLFWwindow;

namespace vtb::viewer {

/// The controls a session starts with: the options', else the scene's solver when it can run
/// interactively (cvode and fem cannot: then filtered, and `note` says so).
SimControls initial_controls(const Scene& scene, const ViewOptions& options, std::string* note = nullptr);

template <int dim> class App {
public:
  /// Takes the session's simulation (built before the window, so that bad input is found
  /// first) and the note of initial_controls.
  App(GLFWwindow* window, const Scene& scene, std::unique_ptr<LiveSim<dim>> sim, std::string note,
      const ViewOptions& options, std::unique_ptr<HapticDevice> driver = nullptr);

  /// One frame: advance the physics by sim_seconds within wall_budget, then draw.
  void frame(double sim_seconds, double wall_budget);
  /// Holds the scripted drag (scene points) as a pinned pull.
  void start_drag(const Eigen::Vector3d& from, const Eigen::Vector3d& to);
  const LiveSim<dim>& sim() const { return *m_sim; }
  /// Device mode: on or off (3D: the device acts in the scene's [haptics.plane]).
  void set_device_mode(bool on);
  /// Where the hand holds the handle in device mode (a scene point, taken to the device's plane).
  void set_hand(const Eigen::Vector3d& p);
  const DeviceMode<dim>* device() const { return m_device.get(); }
  double last_physics_seconds() const { return m_physics_seconds; }

private:
  void layout();
  void handle_mouse();
  void draw_body();
  void draw_markers();
  void draw_pulls();
  void draw_device();
  /// The device's tool tip and its footprint, drawn through `at` (a body point to the window).
  template <class At> void draw_tip(ImDrawList* fg, const At& at) const;
  void draw_device_panel();
  void draw_panel();
  void draw_solver_controls();
  void draw_run_controls();
  void draw_readouts();
  void draw_messages();
  void draw_scale_bar();
  Eigen::Vector3d to3(const Vec<dim>& p) const;
  Vec<dim> from3(const Eigen::Vector3d& p) const;

  GLFWwindow* m_window;
  std::unique_ptr<LiveSim<dim>> m_sim;
  Surface<dim> m_surface;
  Camera m_cam;
  GlDraw m_gl;
  std::vector<float> m_tris, m_lines, m_points; ///< reused vertex arrays
  std::vector<float> m_strain, m_sorted;        ///< per cell
  std::vector<int> m_fixed, m_loaded;           ///< marked nodes
  bool m_paused = false;
  bool m_color_by_strain = true;
  int m_grab = -1; ///< pull being dragged by the mouse
  bool m_orbiting = false;
  bool m_c_was_down = false;
  Eigen::Vector2d m_last_cursor = Eigen::Vector2d::Zero();
  double m_physics_seconds = 0;
  double m_strain_scale = 0; ///< upper end of the colour bar (grows, never shrinks mid-run)
  double m_disp_scale = 0;
  SimControls m_edit; ///< what the panel edits
  std::string m_message;
  float m_trace[LiveSim<dim>::kTrace] = {};
  float m_force_trace[DeviceMode<dim>::kTrace] = {};
  std::unique_ptr<DeviceMode<dim>> m_device;
  static constexpr int kHandPath = 240;                 ///< hand positions kept for the path drawn
  std::array<Eigen::Vector3d, kHandPath> m_hand_path{}; ///< ring, in the device's plane
  int m_hand_head = 0, m_hand_count = 0;
  bool m_device_on = false;
  bool m_scripted = false;
  const Scene* m_scene = nullptr;
  std::unique_ptr<HapticDevice> m_driver; ///< open_device_driver's, until device mode first takes it
  bool m_has_driver = false;
  double m_wall_start = 0;
};

} // namespace vtb::viewer
