#include "viewer.hh"

#include "app.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"
#include "vtb/haptics/device_plane.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/solvers/filter_pick.hh"
#include "vtb/solvers/simulation.hh"
#include "vtb/springs/model.hh"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <vector>

namespace vtb::viewer {
namespace {

/// GLFW and ImGui, set up and torn down in order (RAII); no global state of ours.
class Window {
public:
  Window(const ViewOptions& o, const std::string& title) {
    glfwSetErrorCallback([](int, const char*) {});
    if (!glfwInit())
      throw NoDisplay("vtb view: no display to open a window on (set DISPLAY, or run it under xvfb-run -a)");
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_SAMPLES, 4);
    m_window = glfwCreateWindow(o.width, o.height, title.c_str(), nullptr, nullptr);
    if (!m_window) {
      glfwTerminate();
      throw NoDisplay("vtb view: cannot create an OpenGL 3.3 core window on this display");
    }
    glfwMakeContextCurrent(m_window);
    glfwSwapInterval(o.frames > 0 ? 0 : 1);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr; // no imgui.ini written beside the user's files
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(m_window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
  }
  ~Window() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(m_window);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* get() const { return m_window; }

private:
  GLFWwindow* m_window = nullptr;
};

/// The back buffer as an RGB PNG (rows flipped: OpenGL's origin is bottom left). The file is
/// written to a temporary name and renamed, so a failed write leaves nothing behind.
void write_png(GLFWwindow* w, const std::string& path) {
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(w, &fw, &fh);
  std::vector<unsigned char> px(static_cast<std::size_t>(fw) * fh * 3), flipped(px.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, fw, fh, GL_RGB, GL_UNSIGNED_BYTE, px.data());
  const std::size_t row = static_cast<std::size_t>(fw) * 3;
  for (int y = 0; y < fh; ++y)
    std::copy_n(px.begin() + static_cast<std::ptrdiff_t>(row * static_cast<std::size_t>(fh - 1 - y)), row,
                flipped.begin() + static_cast<std::ptrdiff_t>(row * static_cast<std::size_t>(y)));
  commit_file_atomically(path, [&](const std::filesystem::path& tmp) {
    return stbi_write_png(tmp.c_str(), fw, fh, 3, flipped.data(), static_cast<int>(row)) != 0;
  });
}

template <int dim>
int session(Window& win, const Scene& scene, std::unique_ptr<LiveSim<dim>> live, std::string note, const ViewOptions& o,
            std::unique_ptr<HapticDevice> driver) {
  App<dim> app(win.get(), scene, std::move(live), std::move(note), o, std::move(driver));
  if (o.device) app.set_device_mode(true);
  if (o.drag && !o.device) app.start_drag(o.drag->first, o.drag->second);
  const bool headless = o.frames > 0;
  double last = glfwGetTime(), frame_sum = 0, physics_sum = 0;
  std::vector<double> frame_times;
  for (int f = 0; headless ? f < o.frames : !glfwWindowShouldClose(win.get()); ++f) {
    glfwPollEvents();
    const double now = glfwGetTime();
    // Scripted: a fixed 1/60 s of simulated time per frame (deterministic pictures).
    // Interactive: the wall time since the last frame, at most 1/10 s (a stall is not replayed;
    // a large body's frame, its drawing and a step of tens of ms, still is).
    const double sim_dt = headless ? 1.0 / 60 : std::min(now - last, 0.1);
    last = now;
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    // A scripted device session: the hand moves from the drag's first point to its second
    // over the first half of the frames, then holds.
    if (headless && o.device && o.drag)
      app.set_hand(o.drag->first + std::min(1.0, 2.0 * f / o.frames) * (o.drag->second - o.drag->first));
    app.frame(sim_dt, headless ? 1e9 : 0.6 / 60);
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (headless && f + 1 == o.frames && !o.screenshot.empty()) write_png(win.get(), o.screenshot);
    glfwSwapBuffers(win.get());
    const double frame = glfwGetTime() - now;
    frame_times.push_back(frame);
    frame_sum += frame;
    physics_sum += app.last_physics_seconds();
  }
  if (headless) {
    std::sort(frame_times.begin(), frame_times.end());
    const auto& sim = app.sim();
    std::cout << "vtb view: " << o.frames << " frames of " << scene.name << " (" << sim.model().num_nodes()
              << " nodes, " << sim.controls().solver << ", dt = " << sim.controls().dt << " s); frame "
              << frame_times[frame_times.size() / 2] * 1e3 << " ms median, physics " << physics_sum / o.frames * 1e3
              << " ms/frame, step " << sim.stats().step_median_us << " us median; max strain " << sim.stats().max_strain
              << "; pulls " << sim.num_pulls();
    for (int k = 0; k < sim.num_pulls(); ++k) std::cout << (k ? ", " : " (") << sim.pull_force(k).norm() << " N";
    std::cout << (sim.num_pulls() ? ")" : "") << "\n";
    if (const DeviceMode<dim>* d = app.device())
      std::cout << "vtb view: device: " << d->device_name() << ", " << d->ticks()
                << " servo ticks, |F| = " << d->force().norm() << " N, saturated " << d->saturated() << ", "
                << (d->touching() ? "in contact" : "free") << "\n";
    if (!sim.failure().empty()) std::cout << "vtb view: unstable: " << sim.failure() << "\n";
    if (!o.screenshot.empty()) std::cout << "vtb view: wrote " << o.screenshot << "\n";
  }
  (void)frame_sum;
  return 0;
}

/// A pull's grip must be on the body (the probe rule of scene files): its start farther than the
/// longest edge from every node is a typo or the wrong units, not a pull (a start 700 m from a
/// 0.2 m plate would pull with 10^5 N). Bad input naming the point and the distance.
template <int dim> void check_drag_start(const Model<dim>& model, const Eigen::Vector3d& from) {
  const Vec<dim> p = from.head<dim>();
  const Eigen::Index node = [&] {
    Eigen::Index k = 0;
    (model.mesh.points.colwise() - p).colwise().squaredNorm().minCoeff(&k);
    return k;
  }();
  const double d = (model.mesh.points.col(node) - p).norm();
  const double longest = model.net.rest_length.size() ? model.net.rest_length.maxCoeff() : 0.0;
  if (d > longest) {
    std::ostringstream os;
    os << "--drag: the pull starts at [";
    for (int a = 0; a < dim; ++a) os << (a ? ", " : "") << p[a];
    os << "], " << d << " m from the body (nearest node " << node << "); a pull must start within the longest edge ("
       << longest << " m) of a node";
    throw InputError(os.str());
  }
}

/// Device mode on a body whose step does not fit half a servo period: the physics steps at the
/// rate it affords, as `vtb haptics` runs it (with_physics_rate), and the note says so.
template <int dim> void use_physics_rate(const Scene& scene, LiveSim<dim>& sim, std::string& note) {
  const HapticsDesc h = scene.haptics ? *scene.haptics : HapticsDesc{};
  SimControls c = sim.controls();
  IntegratorOptions io = integrator_options(scene.solver);
  io.kind = c.solver;
  io.filter = c.filter;
  io.dt = c.dt;
  io = with_physics_rate(sim.model(), io, 1.0 / h.rate, TrialCoupling{h.coupling_stiffness, h.coupling_damping});
  if (!(io.dt > c.dt * (1 + 1e-9))) return;
  c.dt = io.dt;
  if (io.kind == solvers::kFiltered) c.filter = io.filter;
  sim.configure(c);
  note +=
      std::string(note.empty() ? "" : "; ") + "device mode steps the body at the rate it affords: " + io.filter_reason;
}

} // namespace

std::pair<Eigen::Vector3d, Eigen::Vector3d> parse_drag(const std::string& text) {
  const auto colon = text.find(':');
  auto point = [&](const std::string& part) {
    std::vector<double> v;
    std::stringstream ss(part);
    for (std::string item; std::getline(ss, item, ',');) {
      char* end = nullptr;
      const double x = std::strtod(item.c_str(), &end);
      if (end == item.c_str() || *end != '\0' || !std::isfinite(x))
        throw InputError("--drag \"" + text + "\": expected X0,Y0:X1,Y1 (or X0,Y0,Z0:X1,Y1,Z1) in scene coordinates");
      v.push_back(x);
    }
    if (v.size() != 2 && v.size() != 3)
      throw InputError("--drag \"" + text + "\": expected X0,Y0:X1,Y1 (or X0,Y0,Z0:X1,Y1,Z1) in scene coordinates");
    return Eigen::Vector3d(v[0], v[1], v.size() == 3 ? v[2] : 0.0);
  };
  if (colon == std::string::npos)
    throw InputError("--drag \"" + text + "\": expected X0,Y0:X1,Y1 (or X0,Y0,Z0:X1,Y1,Z1) in scene coordinates");
  return {point(text.substr(0, colon)), point(text.substr(colon + 1))};
}

int run_viewer(const Scene& scene, const ViewOptions& o) {
  if (o.frames < 0) throw InputError("--frames must be >= 0");
  if (!o.screenshot.empty() && o.frames == 0) throw InputError("--screenshot needs --frames N (the frame to write)");
  if (o.dt) checked_dt(*o.dt);
  AnyMesh mesh = load_mesh(scene);
  return std::visit(
      [&](auto& m) {
        constexpr int dim = std::decay_t<decltype(m)>::points_dim;
        // The simulation is built before the window opens, so that a scene the solvers refuse
        // is reported as bad input (exit 1) whether or not there is a display.
        std::string note;
        auto sim = std::make_unique<LiveSim<dim>>(scene, std::move(m), initial_controls(scene, o, &note), o.yardstick);
        if (o.drag && !o.device) check_drag_start(sim->model(), o.drag->first);
        if (o.device) device_plane(scene, sim->model().mesh); // a plane the scene cannot hold is bad input now
        if (o.device && !o.dt && !scene.solver.dt_given) use_physics_rate(scene, *sim, note);
        // A driver that cannot be opened is bad input too; opened once, it sends 0 N at close.
        auto driver = o.device ? open_device_driver(scene, o.driver) : nullptr;
        Window win(o, "vtb view: " + scene.name);
        return session<dim>(win, scene, std::move(sim), std::move(note), o, std::move(driver));
      },
      mesh);
}

} // namespace vtb::viewer
