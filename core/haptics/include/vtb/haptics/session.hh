#pragma once
/// \file
/// `vtb haptics`: the device servo loop (its own thread, `rate` Hz) coupled through a virtual
/// coupling and the proxy to a 2D or 3D body simulated by a spring solver (multirate: physics
/// at the dt it affords on the main thread, the servo solving the contact against the local
/// model each physics step hands it), with saturation, ramp-in and a watchdog. One or several
/// probes (devices), whose contact forces act on the body in the same physics step.

#include "vtb/haptics/device.hh"
#include "vtb/problem/scene.hh"

#include <filesystem>

namespace vtb {
struct Yardstick; // vtb/springs/load_check.hh
}

namespace vtb {

struct HapticsOptions {
  enum class Fault { none, stall, nan } fault = Fault::none;
  double fault_time = 0;        ///< s of simulated time
  bool lockstep = false;        ///< one thread, servo and physics interleaved in simulated time (deterministic)
  std::filesystem::path replay; ///< for device = "replay": the recorded handle trajectories (haptics.csv)
  // Real-time servo thread set-up (docs/haptics.md measures what each buys on a loaded box).
  bool realtime_priority = true; ///< ask for SCHED_FIFO 80 (granted to root or CAP_SYS_NICE)
  bool lock_memory = false;      ///< mlockall(MCL_CURRENT | MCL_FUTURE) for the session's length
  int pin_cpu = -1;              ///< >= 0: the servo thread pinned to that core, the physics kept off it
  /// What the model's springs are fitted to and checked against (build_model); null: P1 on
  /// the mesh. `vtb haptics` gives the continuum, as `vtb run` does.
  const Yardstick* yardstick = nullptr;
  /// s: the physics' step (> 0), overriding the scene's and the rate the body affords (0: not set).
  double physics_dt = 0;
  /// A physics stepping slower than the servo hands it a local contact model (local_model.hh);
  /// false: the servo couples against the free motion alone (to measure what the model buys).
  bool local_model = true;
  /// Overrides [haptics].device: procat-sim, replay, null, plugin:PATH or udp:HOST:PORT (empty: the scene's).
  std::string device;
};

/// One probe's record: handle position and the force sent to its device, per servo sample
/// (device coordinates), and its totals.
struct ProbeTrace {
  std::vector<double> hx, hy, fx, fy;
  double max_force = 0;
  long saturated_samples = 0, nonfinite_samples = 0;
  double energy_to_user = 0; ///< J: the work the device did on the handle
  /// The tool tip over the servo cycles in contact: how many, the footprint's largest node
  /// count, the cycles where the tip was narrower than the touched facet (the force not
  /// resolved there: a point proxy's) and those where it covered more nodes than it takes.
  long contact_samples = 0, unresolved_samples = 0, truncated_samples = 0;
  int footprint_nodes_max = 0;
};

struct HapticsReport {
  int dim = 2;
  std::string device;   ///< the first device's name (HapticDevice::name)
  DeviceLinkStats link; ///< summed over the devices (a UDP link's, a plug-in's faults)
  long samples = 0;
  double rate_hz_mean = 0, period_p99_us = 0, period_max_us = 0;
  long deadline_misses = 0; ///< cycles that started more than half a period late
  std::vector<std::string>
      realtime_setup; ///< what the servo thread was granted: "fifo", "mlock", "pinned" (or "x-denied")
  /// Over all probes: the largest force, the sums of the counts and of the energy.
  double max_force = 0;
  long saturated_samples = 0, nonfinite_samples = 0;
  double energy_to_user = 0;
  double fault_time = -1, force_zero_time = -1; ///< when the watchdog tripped, when every |F| first hit 0 after it
  std::string fault_reason;                     ///< what tripped it (BasicForceShaper::fault_reason)
  long physics_steps = 0;
  double physics_step_median_us = 0, physics_step_max_us = 0;
  /// The physics' step (us): the scene's dt, or the rate the body affords in real time
  /// (filter_pick.hh: with_physics_rate); and the simulated time it reached over wall time (1:
  /// it kept pace; 1 in lockstep).
  double physics_dt_us = 0, physics_time_ratio = 1;
  /// Where the servo's local contact models took their compliance (local_model.hh): "solver"
  /// (the physics' own system), "half-space" (the tip's, where the solver has none) or "none"
  /// (a physics stepping every servo period: no model between steps).
  std::string local_model;
  /// The local model's error: the coupling force's change at a publish in contact, what it
  /// predicted against what the new physics step gives (N; one servo period of the hand's
  /// motion included).
  double local_model_error_rms = 0, local_model_error_max = 0;
  /// 3D contact trees (the AABB tree of the surface): built by the physics' thread and adopted by
  /// the servo (real time), or built in the servo's cycle (lockstep; real time when the physics
  /// has not kept up).
  long contact_tree_builds_physics = 0, contact_tree_builds_servo = 0;
  /// The physics' step budget: [solver].step_budget, or the servo period when the scene sets
  /// none (one physics step per servo cycle); the steps over it; the filter auto picked within
  /// it and why (filter_pick.hh; empty for other solvers or a named filter).
  double physics_step_budget_us = 0;
  long physics_steps_over_budget = 0;
  std::string physics_filter, physics_filter_reason;
  std::string springs; ///< the spring constants the body runs ("lloyd", "fitted", ...; auto's note in `notes`)
  double tick_median_us = 0, tick_p99_us = 0; ///< the servo cycle's own work (real time only; 0 in lockstep)
  double coupling_stiffness = 0;              ///< N/m rendered: the scene's, limited to the device's max stiffness
  double tip_radius = 0;                      ///< m: the tool tip's (0: a point proxy)
  double surface_mean_edge = 0;               ///< m: the body's mean surface edge at rest
  std::vector<std::string> notes;             ///< what the run changed from the scene, one line each
  std::vector<double> period_us;              ///< each servo cycle's measured period (real time only)
  std::vector<double> t;                      ///< servo sample times
  std::vector<ProbeTrace> probes;             ///< probe 0 is [haptics.hand], then [[haptics.probe]] in order
};

/// Runs the scene's [haptics] session for [scene].duration: a 2D scene, or a 3D one with the
/// device's plane placed by [haptics.plane]. Needs [haptics.hand] (procat-sim) or a replay file.
HapticsReport run_haptics(const Scene& scene, const HapticsOptions& options);

/// The scene with its [haptics].device replaced as `--device SPEC` names it (SPEC empty: as it is).
/// Throws InputError on an unknown SPEC.
Scene with_device(const Scene& scene, const std::string& spec);

/// haptics.csv (t,hx,hy,fx,fy, then hx_k,hy_k,fx_k,fy_k for probe k >= 1) and summary.json
/// into dir, all or nothing.
void write_haptics(const HapticsReport& report, const std::filesystem::path& dir, const std::string& scene_name);

} // namespace vtb
