// The viewer's Dear ImGui panel (live control and readouts) and the colour scale bar.
#include "app.hh"
#include "colormap.hh"
#include "vtb/problem/solver_names.hh"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <cfloat>
#include <cmath>
#include <cstdio>

namespace vtb::viewer {

/// The solver's controls; a change rebuilds the simulation (or says why it cannot).
template <int dim> void App<dim>::draw_solver_controls() {
  const auto& sim = *m_sim;
  ImGui::TextDisabled("solver");
  bool changed = false;
  if (ImGui::BeginCombo("kind", m_edit.solver.c_str())) {
    for (const std::string& k : interactive_solvers())
      if (ImGui::Selectable(k.c_str(), m_edit.solver == k)) {
        m_edit.solver = k;
        changed = true;
      }
    ImGui::EndCombo();
  }
  if (m_edit.solver == solvers::kFiltered && ImGui::BeginCombo("filter", m_edit.filter.c_str())) {
    for (const char* f : kFilterChoices)
      if (ImGui::Selectable(f, m_edit.filter == f)) {
        m_edit.filter = f;
        changed = true;
      }
    ImGui::EndCombo();
  }
  if (sim.controls().filter == solvers::kFilterAuto && !sim.running_filter().empty())
    ImGui::TextDisabled("auto runs the %s filter here", sim.running_filter().c_str());
  if (ImGui::BeginCombo("springs", m_edit.springs.c_str())) {
    for (const char* k : kSprings)
      if (ImGui::Selectable(k, m_edit.springs == k)) {
        m_edit.springs = k;
        changed = true;
      }
    ImGui::EndCombo();
  }
  float log_dt = static_cast<float>(std::log10(m_edit.dt));
  if (ImGui::SliderFloat("log10 dt", &log_dt, -6.0f, -1.0f, "%.2f")) {
    m_edit.dt = std::pow(10.0, static_cast<double>(log_dt));
    changed = true;
  }
  ImGui::Text("dt = %.3g s (explicit limit %.3g s)", m_edit.dt, sim.courant_dt());
  float scale = static_cast<float>(m_edit.stiffness_scale);
  if (ImGui::SliderFloat("stiffness x", &scale, 0.1f, 100.0f, "%.2f", ImGuiSliderFlags_Logarithmic)) {
    m_edit.stiffness_scale = scale;
    changed = true;
  }
  if (changed) {
    try {
      m_sim->configure(m_edit);
      m_message.clear();
    } catch (const std::exception& e) {
      m_message = e.what();
      m_edit = m_sim->controls();
    }
  }
}

/// Pause, single step, reset, the pull's stiffness and the colouring.
template <int dim> void App<dim>::draw_run_controls() {
  ImGui::TextDisabled("run");
  ImGui::Checkbox("pause", &m_paused);
  ImGui::SameLine();
  if (ImGui::Button("step")) m_sim->single_step();
  ImGui::SameLine();
  if (ImGui::Button("reset")) m_sim->reset();
  float k = static_cast<float>(m_sim->coupling_stiffness);
  if (ImGui::SliderFloat("pull N/m", &k, 0.1f, 1e4f, "%.3g", ImGuiSliderFlags_Logarithmic))
    m_sim->coupling_stiffness = k;
  ImGui::Checkbox("colour by strain (else |u|)", &m_color_by_strain);
}

/// Time, step cost, real-time factor, energy, strain, and the probe's trace.
template <int dim> void App<dim>::draw_readouts() {
  const auto& sim = *m_sim;
  const auto& st = sim.stats();
  ImGui::TextDisabled("readouts");
  ImGui::Text("t = %.3f s, %ld steps", sim.state().t, st.steps);
  ImGui::Text("step %.1f us (median), physics %.2f ms/frame", st.step_median_us, m_physics_seconds * 1e3);
  ImGui::Text("real-time factor %.2f, %.0f frames/s", st.realtime_factor, ImGui::GetIO().Framerate);
  ImGui::Text("energy %.4g J, max spring strain %.3g", st.energy, st.max_strain);
  ImGui::Text("pulls: %d (shift+release pins, C lets go)", sim.num_pulls());
  if (st.fallback_steps > 0)
    ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "tensor: %ld steps by implicit Euler", st.fallback_steps);
  if (st.step_budget_us > 0)
    ImGui::TextColored(st.steps_over_budget > 0 ? ImVec4(1, 0.6f, 0.1f, 1) : ImVec4(0.7f, 0.9f, 0.7f, 1),
                       "step budget %.0f us: %ld steps over", st.step_budget_us, st.steps_over_budget);
  if (st.behind && !m_paused) ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "behind real time: physics over budget");
  const int n = sim.probe_trace(m_trace);
  if (n > 0) {
    char label[96];
    std::snprintf(label, sizeof label, "|u| at probe \"%s\"", sim.probe_name().c_str());
    ImGui::Text("%s", label);
    ImGui::PlotLines("##trace", m_trace, n, 0, nullptr, 0.0f, FLT_MAX, ImVec2(300, 80));
  }
}

/// An unstable run (with its reset) and the last refused change.
template <int dim> void App<dim>::draw_messages() {
  const auto& sim = *m_sim;
  if (!sim.failure().empty()) {
    ImGui::PushTextWrapPos(320);
    ImGui::TextColored(ImVec4(1, 0.2f, 0.2f, 1), "UNSTABLE: %s", sim.failure().c_str());
    ImGui::PopTextWrapPos();
    if (ImGui::Button("reset the run")) m_sim->reset();
  }
  if (!m_message.empty()) {
    ImGui::PushTextWrapPos(320);
    ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "%s", m_message.c_str());
    ImGui::PopTextWrapPos();
  }
}

template <int dim> void App<dim>::draw_panel() {
  const auto& sim = *m_sim;
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(330, ImGui::GetIO().DisplaySize.y));
  ImGui::Begin("vtb", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  const auto& net = sim.model().net;
  ImGui::Text("%d nodes, %d springs, %s", sim.model().num_nodes(), net.num_springs(),
              dim == 2 ? "2D plate" : "3D solid");
  if (std::isfinite(net.calibration_validation))
    ImGui::Text("springs: %s, held-out error %.1f %%", net.calibration.c_str(), 100 * net.calibration_validation);
  else
    ImGui::Text("springs: %s", net.calibration.c_str());
  if (std::isfinite(net.calibration_load_error) && std::isfinite(net.mesh_fem_load_error))
    ImGui::Text("%.1f %% from the continuum on the scene's loads%s\n(P1 on this mesh: %.1f %%)",
                100 * net.calibration_load_error, net.calibration_own_loads ? ", trained on" : "",
                100 * net.mesh_fem_load_error);
  else if (std::isfinite(net.calibration_load_error))
    ImGui::Text("%.1f %% from P1 FEM on the scene's loads", 100 * net.calibration_load_error);
  if (!net.calibration_note.empty()) {
    ImGui::PushTextWrapPos(320);
    ImGui::TextDisabled("%s", net.calibration_note.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::Separator();
  draw_solver_controls();
  ImGui::Separator();
  draw_run_controls();
  ImGui::Separator();
  draw_readouts();
  draw_messages();
  draw_device_panel();
  ImGui::Separator();
  ImGui::TextDisabled("mouse");
  ImGui::TextWrapped("left drag: pull the nearest boundary point; right drag: %s; wheel: zoom",
                     dim == 3 ? "orbit" : "pan");
  ImGui::End();
}

template <int dim> void App<dim>::draw_device_panel() {
  ImGui::Separator();
  ImGui::TextDisabled("device");
  bool on = m_device_on;
  if (ImGui::Checkbox(!m_has_driver ? "device mode: the mouse holds the ProCAT"
                                    : "device mode: the driver's handle",
                      &on))
    set_device_mode(on);
  if (!m_device_on || !m_device) return;
  const DeviceMode<dim>& d = *m_device;
  if constexpr (dim == 3) {
    const auto& pl = d.plane();
    ImGui::TextWrapped("plane: origin (%.3g, %.3g, %.3g), x (%.2g, %.2g, %.2g), y (%.2g, %.2g, %.2g)", pl.origin.x(),
                       pl.origin.y(), pl.origin.z(), pl.axes(0, 0), pl.axes(1, 0), pl.axes(2, 0), pl.axes(0, 1),
                       pl.axes(1, 1), pl.axes(2, 1));
  }
  ImGui::Text("device: %s", d.device_name().c_str());
  const double wall = glfwGetTime() - m_wall_start;
  ImGui::Text("servo: 1 kHz of simulated time (lockstep)");
  ImGui::Text("%ld ticks, %.0f per wall second", d.ticks(), wall > 0 ? d.ticks() / wall : 0.0);
  ImGui::Text("%s, |F| = %.3g N (limit %.3g N)", d.touching() ? "in contact" : "free", d.force().norm(), d.max_force());
  ImGui::Text("saturated ticks: %ld%s", d.saturated(), d.faulted() ? ", WATCHDOG TRIPPED" : "");
  const int n = d.force_trace(m_force_trace);
  if (n > 0) ImGui::PlotLines("|F| N", m_force_trace, n, 0, nullptr, 0.0f, FLT_MAX, ImVec2(260, 70));
}

template <int dim> void App<dim>::draw_scale_bar() {
  // A vertical bar at the right edge: the colour scale with its numbers.
  ImDrawList* fg = ImGui::GetForegroundDrawList();
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  const float x0 = size.x - 100, x1 = size.x - 80, y0 = 40, y1 = size.y - 60;
  const int steps = 32;
  for (int i = 0; i < steps; ++i) {
    const double s0 = static_cast<double>(i) / steps, s1 = static_cast<double>(i + 1) / steps;
    const auto c0 = viridis(s0), c1 = viridis(s1);
    const float ya = y1 - static_cast<float>(s0) * (y1 - y0), yb = y1 - static_cast<float>(s1) * (y1 - y0);
    fg->AddRectFilledMultiColor(ImVec2(x0, yb), ImVec2(x1, ya), ImColor(c1[0], c1[1], c1[2]),
                                ImColor(c1[0], c1[1], c1[2]), ImColor(c0[0], c0[1], c0[2]),
                                ImColor(c0[0], c0[1], c0[2]));
  }
  fg->AddRect(ImVec2(x0, y0), ImVec2(x1, y1), IM_COL32(40, 40, 40, 255));
  const double top = m_color_by_strain ? m_strain_scale : m_disp_scale;
  for (int i = 0; i <= 4; ++i) {
    char label[32];
    std::snprintf(label, sizeof label, "%.2g", top * i / 4);
    fg->AddText(ImVec2(x1 + 4, y1 - (y1 - y0) * static_cast<float>(i) / 4 - 7), IM_COL32(20, 20, 20, 255), label);
  }
  fg->AddText(ImVec2(x0 - 40, y1 + 12), IM_COL32(20, 20, 20, 255), m_color_by_strain ? "max principal" : "|u|, m");
  if (m_color_by_strain) fg->AddText(ImVec2(x0 - 40, y1 + 28), IM_COL32(20, 20, 20, 255), "strain");
}

template void App<2>::draw_panel();
template void App<3>::draw_panel();
template void App<2>::draw_scale_bar();
template void App<2>::draw_device_panel();
template void App<3>::draw_device_panel();
template void App<3>::draw_scale_bar();

} // namespace vtb::viewer
