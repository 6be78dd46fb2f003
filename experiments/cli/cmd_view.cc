#include "commands.hh"

#include "vtb/problem/solver_registry.hh"

#include "../viewer/viewer.hh"
#include "vtb/harness/solvers.hh"

#include <iostream>
#include <memory>
#include <optional>

namespace vtb::cli {

Action add_view(CLI::App& app) {
  struct Opts {
    std::string scene, screenshot, drag, solver, filter;
    int frames = 0;
    std::string device;       ///< empty: off; "procat-sim" (the bare flag) or "plugin:PATH"
    std::optional<double> dt; ///< absent: the scene's
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "view", "The interactive viewer: the body coloured by strain, pulls by mouse, solvers switched live");
  cmd->add_option("scene", o->scene, "Scene file (.toml)")->required();
  cmd->add_option("--frames", o->frames, "Render N frames (1/60 s of simulated time each), then exit");
  cmd->add_option("--screenshot", o->screenshot, "With --frames: write the last frame to this PNG");
  cmd->add_option("--drag", o->drag, "Hold a pull from the first frame: X0,Y0:X1,Y1 in scene coordinates");
  // The steppers, and the filtered scheme's names that fix its filter.
  const auto startable = [](const solvers::Entry& e) { return e.interactive || *e.filter != '\0'; };
  cmd->add_option("--solver", o->solver, "Start with this solver: " + solvers::list(+startable));
  std::string filters; // from the names' table, so that a new filter is listed (solver_names.hh)
  for (const char* f : solvers::kFilterChoices) filters += (filters.empty() ? "" : " | ") + std::string(f);
  cmd->add_option("--filter", o->filter, "Start with this filter: " + filters);
  cmd->add_option("--dt", o->dt, "Start with this time step (s)");
  cmd->add_flag("--device{procat-sim}", o->device,
                "Device mode: the mouse, or the --drag path, is the hand on the simulated ProCAT (3D: in the scene's "
                "[haptics.plane]); --device=plugin:PATH: a driver's shared library (device_abi.h) is the device, "
                "opened with the scene's [haptics].plugin_config, and its handle moves the tool");
  return [o]() {
    const Scene scene = read_scene(o->scene);
    viewer::ViewOptions v;
    v.frames = o->frames;
    v.screenshot = o->screenshot;
    if (!o->drag.empty()) v.drag = viewer::parse_drag(o->drag);
    if (!o->solver.empty()) v.solver = o->solver;
    if (!o->filter.empty()) v.filter = o->filter;
    v.dt = o->dt;
    v.device = !o->device.empty();
    v.driver = o->device;
    v.yardstick = harness::continuum_yardstick();
    try {
      return viewer::run_viewer(scene, v);
    } catch (const viewer::NoDisplay& e) {
      std::cerr << "vtb: error: " << e.what() << "\n";
      return 3;
    }
  };
}

} // namespace vtb::cli
