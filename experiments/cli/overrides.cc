#include "overrides.hh"

#include "vtb/meshes/input_error.hh"
#include "vtb/problem/solver_registry.hh"

#include <algorithm>
#include <cmath>

namespace vtb::cli {

Scene with_overrides(const Scene& scene_in, const RunOverrides& ov) {
  Scene scene = scene_in;
  // Any registry name: a kind, or a kind with its filter (filtered-tensor).
  if (ov.solver) solvers::select(*ov.solver, "--solver", scene.solver.kind, scene.solver.filter);
  if (ov.dt) {
    if (!(*ov.dt > 0) || !std::isfinite(*ov.dt)) throw InputError("--dt must be a positive number");
    scene.solver.dt = *ov.dt;
  }
  if (ov.duration) {
    if (!(*ov.duration > 0) || !std::isfinite(*ov.duration)) throw InputError("--duration must be a positive number");
    scene.duration = *ov.duration;
    scene.output_interval = std::min(scene.output_interval, scene.duration);
  }
  if (scene.solver.dt > scene.duration)
    throw InputError("dt " + std::to_string(scene.solver.dt) + " exceeds the duration");
  return scene;
}

HapticsOptions::Fault parse_fault(const std::string& spec, double& time) {
  const auto at = spec.find('@');
  const std::string kind = spec.substr(0, at);
  if (at == std::string::npos || (kind != "stall" && kind != "nan"))
    throw InputError("--fault \"" + spec + "\": expected stall@T or nan@T (T in seconds)");
  try {
    std::size_t used = 0;
    time = std::stod(spec.substr(at + 1), &used);
    if (used != spec.size() - at - 1 || !(time >= 0) || !std::isfinite(time)) throw std::invalid_argument("");
  } catch (const std::exception&) {
    throw InputError("--fault \"" + spec + "\": T must be a time >= 0 in seconds");
  }
  return kind == "stall" ? HapticsOptions::Fault::stall : HapticsOptions::Fault::nan;
}

} // namespace vtb::cli
