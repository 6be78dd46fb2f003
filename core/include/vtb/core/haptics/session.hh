#pragma once
/// \file
/// `vtb haptics`: the device servo loop (its own thread, `rate` Hz) coupled through a virtual
/// coupling and the proxy to a 2D body simulated by a spring solver (multirate: physics at its
/// own dt on the main thread), with saturation, ramp-in and a watchdog.

#include "vtb/core/scene.hh"

#include <filesystem>

namespace vtb {

struct HapticsOptions {
  enum class Fault { none, stall, nan } fault = Fault::none;
  double fault_time = 0;        ///< s of simulated time
  bool lockstep = false;        ///< one thread, servo and physics interleaved in simulated time (deterministic)
  std::filesystem::path replay; ///< for device = "replay": the recorded handle trajectory
};

/// Parses "stall@T" or "nan@T". Throws InputError otherwise.
HapticsOptions::Fault parse_fault(const std::string& spec, double& time);

struct HapticsReport {
  long samples = 0;
  double rate_hz_mean = 0, period_p99_us = 0, period_max_us = 0;
  long deadline_misses = 0; ///< cycles that started more than half a period late
  double max_force = 0;
  long saturated_samples = 0, nonfinite_samples = 0;
  double energy_to_user = 0;                    ///< J: the work the device did on the handle
  double fault_time = -1, force_zero_time = -1; ///< when the watchdog tripped, when |F| first hit 0 after it
  long physics_steps = 0;
  double physics_step_median_us = 0;
  /// The servo samples: t, handle position, commanded force.
  std::vector<double> t, hx, hy, fx, fy;
};

/// Runs the scene's [haptics] session for [scene].duration. Requires a 2D scene with
/// [haptics] and [haptics.hand] (procat-sim) or a replay file.
HapticsReport run_haptics(const Scene& scene, const HapticsOptions& options);

/// haptics.csv (t,hx,hy,fx,fy) and summary.json into dir, all or nothing.
void write_haptics(const HapticsReport& report, const std::filesystem::path& dir, const std::string& scene_name);

} // namespace vtb
