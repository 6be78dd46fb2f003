#include "app.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/problem/solver_registry.hh"

#include "colormap.hh"

#include "vtb/problem/cell_fields.hh"

#include "vtb/base/input_error.hh"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vtb::viewer {
namespace {

constexpr float kPanelWidth = 330.0f; ///< pixels, the ImGui panel on the left
constexpr float kBarWidth = 150.0f;   ///< pixels, the colour scale on the right
const float kEdge[3] = {0.10f, 0.10f, 0.12f};
const float kFixed[3] = {0.20f, 0.45f, 1.00f};
const float kProbe[3] = {1.00f, 0.25f, 0.25f};
const float kLoad[3] = {1.00f, 0.60f, 0.10f};
const float kArrow[3] = {1.00f, 1.00f, 1.00f};

} // namespace

SimControls initial_controls(const Scene& scene, const ViewOptions& options, std::string* note) {
  const auto names = interactive_solvers();
  const bool interactive = std::find(names.begin(), names.end(), scene.solver.kind) != names.end();
  SimControls c;
  c.solver = interactive ? scene.solver.kind : solvers::kFiltered;
  c.filter = scene.solver.step.filter;
  c.dt = scene.solver.dt;
  c.springs = scene.solver.springs;
  // --solver takes any registry name (filtered-tensor: filtered with the tensor filter); an
  // explicit --filter wins over the one a name implies.
  SolverOverrides{options.solver, options.filter, options.dt, {}}.apply(c.solver, c.filter, c.dt, c.springs);
  if (!interactive && !options.solver && note)
    *note = "the scene's solver \"" + scene.solver.kind + "\" is not interactive; running filtered";
  return c;
}

template <int dim>
App<dim>::App(GLFWwindow* window, const Scene& scene, std::unique_ptr<LiveSim<dim>> sim, std::string note,
              const ViewOptions& options, std::unique_ptr<HapticDevice> driver)
    : m_window(window), m_sim(std::move(sim)), m_surface(make_surface(m_sim->model().mesh)), m_edit(m_sim->controls()),
      m_message(std::move(note)) {
  m_scene = &scene;
  m_has_driver = driver != nullptr;
  m_driver = std::move(driver);
  m_scripted = options.frames > 0; // a scripted run ignores the (absent) mouse
  m_wall_start = glfwGetTime();
  const auto& model = m_sim->model();
  for (const auto& sup : model.supports)
    for (int n : sup.nodes) m_fixed.push_back(n);
  for (const auto& load : model.loads)
    for (int n : load.nodes) m_loaded.push_back(n);
  // Frame the rest shape.
  const auto& X = model.net.rest;
  const Vec<dim> lo = X.rowwise().minCoeff(), hi = X.rowwise().maxCoeff();
  m_cam.perspective = dim == 3;
  m_cam.center = to3(0.5 * (lo + hi));
  m_cam.extent = dim == 2 ? 0.8 * (hi - lo)[1] : 0.5 * (hi - lo).norm();
  if constexpr (dim == 2) {
    // Fit the width too: the half-width extent * aspect covers the plate with a third of its
    // length to spare on each side (room for it to stretch and for the pulls).
    const double aspect = (options.width - kPanelWidth - kBarWidth) / static_cast<double>(options.height);
    m_cam.extent = std::max(m_cam.extent, 0.5 * (hi - lo)[0] * 1.35 / aspect);
  }
}

template <int dim> Eigen::Vector3d App<dim>::to3(const Vec<dim>& p) const {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  q.head<dim>() = p;
  return q;
}
template <int dim> Vec<dim> App<dim>::from3(const Eigen::Vector3d& p) const {
  return p.head<dim>();
}

template <int dim> void App<dim>::start_drag(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const int node = nearest_of<dim>(m_surface.boundary_nodes, m_sim->model().mesh, m_sim->state().u, from3(from));
  Vec<dim> target = from3(to);
  if constexpr (dim == 3) {
    if (std::abs(to.z()) == 0 && std::abs(from.z()) == 0) target.z() = m_sim->position(node).z();
  }
  m_sim->add_pull(node, target, true);
}

template <int dim> void App<dim>::set_device_mode(bool on) {
  if (on && !m_device) m_device = std::make_unique<DeviceMode<dim>>(m_sim->model().mesh, *m_scene, std::move(m_driver));
  m_device_on = on;
  m_sim->set_hook(on ? m_device.get() : nullptr);
}

template <int dim> void App<dim>::set_hand(const Eigen::Vector3d& p) {
  if (!m_device) return;
  m_device->set_hand(from3(p));
  m_hand_path[static_cast<std::size_t>(m_hand_head)] = to3(m_device->hand());
  m_hand_head = (m_hand_head + 1) % kHandPath;
  m_hand_count = std::min(m_hand_count + 1, kHandPath);
}

template <int dim> void App<dim>::layout() {
  int fw = 0, fh = 0, ww = 0, wh = 0;
  glfwGetFramebufferSize(m_window, &fw, &fh);
  glfwGetWindowSize(m_window, &ww, &wh);
  const double scale = ww > 0 ? static_cast<double>(fw) / ww : 1.0;
  m_cam.left = static_cast<int>(kPanelWidth * scale);
  m_cam.width = std::max(1, fw - m_cam.left - static_cast<int>(kBarWidth * scale));
  m_cam.height = std::max(1, fh);
}

template <int dim> void App<dim>::handle_mouse() {
  ImGuiIO& io = ImGui::GetIO();
  double cx = 0, cy = 0;
  glfwGetCursorPos(m_window, &cx, &cy);
  int fw = 0, ww = 1;
  glfwGetFramebufferSize(m_window, &fw, nullptr);
  glfwGetWindowSize(m_window, &ww, nullptr);
  const Eigen::Vector2d cursor = Eigen::Vector2d(cx, cy) * (static_cast<double>(fw) / std::max(1, ww));
  const bool shift = glfwGetKey(m_window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                     glfwGetKey(m_window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  const bool in_view = cursor.x() > m_cam.left && cursor.x() < m_cam.left + m_cam.width;
  if (m_device_on && m_device && in_view && !io.WantCaptureMouse && !m_scripted) {
    // The hand moves in the device's plane: the cursor's ray meets it (2D: the plate's plane).
    const auto& plane = m_device->plane();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    if constexpr (dim == 3) normal = plane.axes.col(0).cross(plane.axes.col(1));
    set_hand(m_cam.on_plane(cursor, to3(plane.origin), normal));
  }
  if (!io.WantCaptureMouse) {
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !m_device_on) {
      // Grab the boundary node nearest to the cursor on the screen.
      int best = -1;
      double d = 1e30;
      for (int n : m_surface.boundary_nodes) {
        const double dn = (m_cam.to_window(to3(m_sim->position(n))) - cursor).squaredNorm();
        if (dn < d) {
          d = dn;
          best = n;
        }
      }
      if (best >= 0) m_grab = m_sim->add_pull(best, m_sim->position(best));
    }
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Right)) m_orbiting = true;
    if (io.MouseWheel != 0) m_cam.zoom *= std::pow(1.15, io.MouseWheel);
    const bool c_down = glfwGetKey(m_window, GLFW_KEY_C) == GLFW_PRESS;
    if (c_down && !m_c_was_down) // C lets go of every pull, pinned or not
      while (m_sim->num_pulls() > 0) m_sim->remove_pull(m_sim->num_pulls() - 1);
    m_c_was_down = c_down;
  }
  if (m_grab >= 0) {
    const Eigen::Vector3d on = to3(m_sim->position(m_sim->pull(m_grab).node));
    m_sim->move_pull(m_grab, from3(m_cam.from_window(cursor, on)));
    if (ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
      if (!shift) m_sim->remove_pull(m_grab);
      m_grab = -1;
    }
  }
  if (m_orbiting) {
    const Eigen::Vector2d d = cursor - m_last_cursor;
    if (m_cam.perspective) {
      m_cam.yaw -= 0.01 * d.x();
      m_cam.pitch = std::clamp(m_cam.pitch + 0.01 * d.y(), -1.5, 1.5);
    } else {
      const double per_px = 2 * m_cam.extent / m_cam.zoom / m_cam.height;
      m_cam.center += Eigen::Vector3d(-d.x() * per_px, d.y() * per_px, 0);
    }
    if (ImGui::IsMouseReleased(ImGuiMouseButton_Right)) m_orbiting = false;
  }
  m_last_cursor = cursor;
}

template <int dim> void App<dim>::draw_body() {
  const auto& model = m_sim->model();
  const auto& u = m_sim->state().u;
  cell_max_principal_strain<dim>(model.mesh, u, m_strain);
  // The colour scale's top is the 98th percentile of the cells' strains, not the maximum: a
  // pull on one node of a membrane makes a near-singular spot that would otherwise leave the
  // rest of the body one colour. It follows a rise at once and a fall slowly (3 % a frame,
  // halving in about 23 frames), so that the colours do not flicker.
  m_sorted = m_strain;
  for (float& s : m_sorted)
    if (!std::isfinite(s)) s = 0;
  const auto q = m_sorted.begin() + static_cast<std::ptrdiff_t>(0.98 * static_cast<double>(m_sorted.size() - 1));
  std::nth_element(m_sorted.begin(), q, m_sorted.end());
  const double smax = m_sorted.empty() ? 0.0 : *q;
  double dmax = 0;
  for (int i = 0; i < model.num_nodes(); ++i) dmax = std::max(dmax, u.col(i).norm());
  m_strain_scale = std::max({0.97 * m_strain_scale, smax, 1e-6});
  m_disp_scale = std::max({0.97 * m_disp_scale, dmax, 1e-9});
  m_tris.clear();
  for (std::size_t t = 0; t < m_surface.tris.size(); ++t) {
    const auto& tri = m_surface.tris[t];
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) p[k] = to3(m_sim->position(tri[static_cast<std::size_t>(k)]));
    Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
    for (int k = 0; k < 3; ++k) {
      const double s = m_color_by_strain ? m_strain[static_cast<std::size_t>(m_surface.owner[t])] / m_strain_scale
                                         : u.col(tri[static_cast<std::size_t>(k)]).norm() / m_disp_scale;
      const auto c = viridis(s);
      put(m_tris, p[k], c.data(), n);
    }
  }
  // A light that moves with the camera, above and to the left of the eye: the faces a viewer
  // sees head-on are bright, those turned away darker, at any orbit.
  if constexpr (dim == 3) {
    const Eigen::Vector3d eye = m_cam.direction(); // from the centre toward the eye
    const Eigen::Vector3d right = Eigen::Vector3d::UnitY().cross(eye).normalized(), up = eye.cross(right);
    m_gl.set_light(eye + 0.6 * up - 0.4 * right);
  }
  // Pushed back a little so that the edges drawn over them win the depth test.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  m_gl.draw(m_tris, GlDraw::Mode::triangles, m_cam.mvp(), dim == 3);
  glDisable(GL_POLYGON_OFFSET_FILL);
  m_lines.clear();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  for (const auto& e : m_surface.edges) {
    put(m_lines, to3(m_sim->position(e[0])), kEdge, z);
    put(m_lines, to3(m_sim->position(e[1])), kEdge, z);
  }
  m_gl.draw(m_lines, GlDraw::Mode::lines, m_cam.mvp(), false);
}

template <int dim> void App<dim>::draw_markers() {
  m_points.clear();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  for (int n : m_fixed) put(m_points, to3(m_sim->position(n)), kFixed, z);
  for (int n : m_loaded) put(m_points, to3(m_sim->position(n)), kLoad, z);
  for (const auto& [name, n] : m_sim->model().probes) put(m_points, to3(m_sim->position(n)), kProbe, z);
  m_gl.draw(m_points, GlDraw::Mode::points, m_cam.mvp(), false, 6.0f);
}

template <int dim> void App<dim>::draw_pulls() {
  // Each pull: a line from the grabbed patch's mean to the target and an arrowhead (the force
  // points from the patch toward the target), labelled with its force in newtons, and the
  // patch's nodes as dots.
  m_lines.clear();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  ImDrawList* fg = ImGui::GetForegroundDrawList();
  const float px = 1.0f / std::max(1.0f, ImGui::GetIO().DisplayFramebufferScale.x);
  for (int k = 0; k < m_sim->num_pulls(); ++k) {
    const auto& p = m_sim->pull(k);
    const Eigen::Vector2d a = m_cam.to_window(to3(m_sim->grabbed(k))) * px, b = m_cam.to_window(to3(p.target)) * px;
    for (int q = 0; p.count > 1 && q < p.count; ++q) {
      const Eigen::Vector2d n = m_cam.to_window(to3(m_sim->position(p.nodes[static_cast<std::size_t>(q)]))) * px;
      fg->AddCircleFilled(ImVec2(float(n.x()), float(n.y())), 3.0f, IM_COL32(255, 255, 255, 200));
    }
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    const ImU32 col = p.pinned ? IM_COL32(255, 90, 90, 255) : IM_COL32(255, 255, 255, 255);
    fg->AddLine(ImVec2(float(a.x()), float(a.y())), ImVec2(float(b.x()), float(b.y())), col, 2.5f);
    if (len > 1) {
      const Eigen::Vector2d u = d / len, w(-u.y(), u.x());
      const Eigen::Vector2d tip = b, l = b - 14 * u + 6 * w, r = b - 14 * u - 6 * w;
      fg->AddTriangleFilled(ImVec2(float(tip.x()), float(tip.y())), ImVec2(float(l.x()), float(l.y())),
                            ImVec2(float(r.x()), float(r.y())), col);
    }
    fg->AddCircleFilled(ImVec2(float(a.x()), float(a.y())), 4.0f, col);
    char label[64];
    std::snprintf(label, sizeof label, "%.3g N", m_sim->pull_force(k).norm());
    fg->AddText(ImVec2(float(b.x()) + 8, float(b.y()) - 8), col, label);
    put(m_lines, to3(m_sim->position(p.node)), kArrow, z);
    put(m_lines, to3(p.target), kArrow, z);
  }
}

template <int dim> void App<dim>::frame(double sim_seconds, double wall_budget) {
  layout();
  handle_mouse();
  const double t0 = glfwGetTime();
  if (!m_paused) m_sim->advance(sim_seconds, wall_budget);
  m_physics_seconds = glfwGetTime() - t0;
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(m_window, &fw, &fh);
  glViewport(0, 0, fw, fh);
  glClearColor(0.93f, 0.94f, 0.96f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glViewport(m_cam.left, 0, m_cam.width, m_cam.height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  draw_body();
  draw_markers(); // depth-tested: a solid's far side hides its markers
  glDisable(GL_DEPTH_TEST);
  draw_pulls();
  if (m_device_on) draw_device();
  glViewport(0, 0, fw, fh);
  draw_panel();
  draw_scale_bar();
}

template <int dim> template <class At> void App<dim>::draw_tip(ImDrawList* fg, const At& at) const {
  // The tool tip (a flat pad of the scene's tip_radius) at the proxy, in its face's plane: a
  // segment in 2D, a circle in 3D (red), and the footprint's nodes it presses (dots sized by
  // their share of the force). Nothing for a point proxy.
  const double r = m_device->tip_radius();
  const Vec<dim> n = m_device->tip_normal(), p = m_device->proxy();
  if (!(r > 0)) return; // a point proxy: its dot is drawn already
  if (n.squaredNorm() > 0) {
    if constexpr (dim == 2) {
      const Vec<2> t(-n.y(), n.x());
      fg->AddLine(at(Vec<2>(p - r * t)), at(Vec<2>(p + r * t)), IM_COL32(200, 30, 30, 255), 4.0f);
    } else {
      const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
      constexpr int kSides = 32;
      ImVec2 ring[kSides];
      for (int k = 0; k < kSides; ++k) {
        const double a = 2 * M_PI * k / kSides;
        ring[k] = at(Vec<3>(p + r * (std::cos(a) * e1 + std::sin(a) * e2)));
      }
      fg->AddPolyline(ring, kSides, IM_COL32(200, 30, 30, 255), ImDrawFlags_Closed, 2.5f);
    }
  }
  const Footprint& fp = m_device->footprint();
  for (int k = 0; k < fp.count; ++k)
    fg->AddCircleFilled(at(Vec<dim>(m_device->positions().col(fp.node[static_cast<std::size_t>(k)]))),
                        2.0f + 10.0f * static_cast<float>(std::sqrt(fp.weight[static_cast<std::size_t>(k)])),
                        IM_COL32(200, 30, 30, 160));
}

template <int dim> void App<dim>::draw_device() {
  // The hand's recent path in the device's plane (grey), the grip from hand to handle, the
  // handle (white), its proxy on the surface (red), and the force the device renders as an
  // arrow from the handle, its length 20 px plus 150 px at the device's force limit.
  if (!m_device) return;
  ImDrawList* fg = ImGui::GetForegroundDrawList();
  const float px = 1.0f / std::max(1.0f, ImGui::GetIO().DisplayFramebufferScale.x);
  auto at3 = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d w = m_cam.to_window(p) * px;
    return ImVec2(static_cast<float>(w.x()), static_cast<float>(w.y()));
  };
  auto at = [&](const Vec<dim>& p) { return at3(to3(p)); };
  for (int k = 1; k < m_hand_count; ++k) {
    const auto i = static_cast<std::size_t>((m_hand_head - m_hand_count + k - 1 + kHandPath) % kHandPath);
    fg->AddLine(at3(m_hand_path[i]), at3(m_hand_path[(i + 1) % kHandPath]), IM_COL32(90, 90, 90, 200), 2.0f);
  }
  const ImVec2 hand = at(m_device->hand()), h = at(m_device->handle()), q = at(m_device->proxy());
  fg->AddLine(hand, h, IM_COL32(90, 90, 90, 255), 1.5f);
  fg->AddCircle(hand, 5.0f, IM_COL32(60, 60, 60, 255), 0, 1.5f);
  if (m_device->touching()) {
    fg->AddLine(h, q, IM_COL32(255, 80, 80, 255), 2.0f);
    fg->AddCircleFilled(q, 6.0f, IM_COL32(255, 60, 60, 255));
    draw_tip(fg, at);
  }
  fg->AddCircleFilled(h, 7.0f, IM_COL32(255, 255, 255, 255));
  fg->AddCircle(h, 7.0f, IM_COL32(30, 30, 30, 255), 0, 2.0f);
  const Vec<dim> f = m_device->force();
  if (f.norm() > 1e-6) {
    // The arrow's screen direction: the force's direction seen through the camera.
    const ImVec2 ahead = at(m_device->handle() + (0.05 * m_cam.extent / f.norm()) * f);
    Eigen::Vector2d u(ahead.x - h.x, ahead.y - h.y);
    if (u.norm() < 1e-9) u = Eigen::Vector2d(0, -1);
    u.normalize();
    const double len = 20 + 150 * f.norm() / m_device->max_force();
    const ImVec2 tip(h.x + static_cast<float>(len * u.x()), h.y + static_cast<float>(len * u.y()));
    fg->AddLine(h, tip, IM_COL32(20, 20, 20, 255), 3.0f);
    const Eigen::Vector2d w(-u.y(), u.x());
    auto off = [&](double a, double b) {
      return ImVec2(tip.x + static_cast<float>(a * u.x() + b * w.x()),
                    tip.y + static_cast<float>(a * u.y() + b * w.y()));
    };
    fg->AddTriangleFilled(tip, off(-12, 6), off(-12, -6), IM_COL32(20, 20, 20, 255));
    char label[48];
    std::snprintf(label, sizeof label, "F = %.3g N", f.norm());
    fg->AddText(ImVec2(tip.x + 8, tip.y - 8), IM_COL32(20, 20, 20, 255), label);
  }
}

template class App<2>;
template class App<3>;

} // namespace vtb::viewer
