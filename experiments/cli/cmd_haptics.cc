#include "commands.hh"
#include "overrides.hh"

#include "vtb/haptics/session.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/problem/support_notes.hh"

#include <algorithm>
#include <iostream>
#include <memory>
#include <thread>

namespace vtb::cli {

Action add_haptics(CLI::App& app) {
  struct Opts {
    std::string scene, fault, out, replay, device;
    bool lockstep = false, lock_memory = false, no_priority = false, no_local_model = false;
    int pin_cpu = -1;
    double physics_dt = 0;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "haptics", "The simulated ProCAT's servo loop against the scene's body (haptics.csv, summary.json)");
  cmd->add_option("scene", o->scene, "Scene file with [haptics] (.toml)")->required();
  cmd->add_option("--fault", o->fault, "Inject a fault: stall@T (physics stops) or nan@T (physics returns NaN)");
  cmd->add_option("--device", o->device,
                  "The device, overriding [haptics].device: procat-sim, replay, null, plugin:PATH (a driver's shared "
                  "library, docs/devices.md) or udp:HOST:PORT (a device in another process)");
  cmd->add_option("--replay", o->replay, "Recorded handle trajectory (t,hx,hy CSV) for device = \"replay\"");
  cmd->add_flag("--lockstep", o->lockstep, "Interleave servo and physics in simulated time (deterministic)");
  cmd->add_flag("--lock-memory", o->lock_memory, "mlockall for the session (no page faults in the servo loop)");
  cmd->add_option("--pin-cpu", o->pin_cpu, "Pin the servo thread to this core; the physics runs on the others");
  cmd->add_flag("--no-realtime-priority", o->no_priority, "Do not ask for SCHED_FIFO (to measure what it buys)");
  CLI::Option* physics_dt = cmd->add_option(
      "--physics-dt", o->physics_dt,
      "The physics' step in s (default: the scene's [solver] dt, else the rate the body affords in real "
      "time, the servo's period in lockstep)");
  cmd->add_flag("--no-local-model", o->no_local_model,
                "The servo couples against the body's free motion alone between physics steps (to measure what the "
                "local contact model buys)");
  cmd->add_option("--out", o->out, "Output folder (default: vtb-out/<scene>-haptics)");
  return [o, physics_dt]() {
    const Scene scene = read_scene(o->scene);
    HapticsOptions ho;
    if (!o->fault.empty()) ho.fault = parse_fault(o->fault, ho.fault_time);
    ho.lockstep = o->lockstep;
    if (physics_dt->count() > 0 && !(o->physics_dt > 0))
      throw InputError("--physics-dt " + std::to_string(o->physics_dt) + ": must be > 0");
    ho.physics_dt = o->physics_dt;
    ho.local_model = !o->no_local_model;
    ho.lock_memory = o->lock_memory;
    const int cores = static_cast<int>(std::thread::hardware_concurrency());
    if (o->pin_cpu >= cores && cores > 0)
      throw InputError("--pin-cpu " + std::to_string(o->pin_cpu) + ": this machine has cores 0-" +
                       std::to_string(cores - 1));
    ho.pin_cpu = o->pin_cpu;
    ho.realtime_priority = !o->no_priority;
    ho.replay = o->replay;
    ho.device = o->device;
    const Yardstick yardstick = harness::continuum_yardstick(); // the default springs, as vtb run's
    ho.yardstick = &yardstick;
    for (const auto& note : support_face_notes(scene)) std::cerr << "note: " << note << '\n';
    const HapticsReport r = run_haptics(scene, ho);
    for (const auto& note : r.notes) std::cerr << "note: " << note << '\n';
    const std::filesystem::path out =
        o->out.empty() ? std::filesystem::path("vtb-out") / (scene.name + "-haptics") : std::filesystem::path(o->out);
    write_haptics(r, out, scene.name);
    std::cout << "vtb haptics: " << r.samples << " servo samples at " << r.rate_hz_mean << " Hz (p99 period "
              << r.period_p99_us << " us, " << r.deadline_misses << " deadline misses), max force " << r.max_force
              << " N, " << r.saturated_samples << " saturated, " << r.nonfinite_samples
              << " non-finite, energy to user " << r.energy_to_user << " J";
    if (r.fault_time >= 0)
      std::cout << "; fault (" << r.fault_reason << ") at " << r.fault_time << " s, force zero at " << r.force_zero_time
                << " s";
    std::cout << "; physics every " << r.physics_dt_us << " us at " << r.physics_time_ratio
              << "x wall time, step median " << r.physics_step_median_us << " us, " << r.physics_steps_over_budget
              << " of " << r.physics_steps << " steps over its budget of " << r.physics_step_budget_us << " us"
              << (r.physics_filter.empty()
                      ? ""
                      : " (" + r.physics_filter + " filter" +
                            (r.physics_filter_reason.empty() ? "" : ": " + r.physics_filter_reason) + ")");
    int footprint = 0;
    for (const ProbeTrace& p : r.probes) footprint = std::max(footprint, p.footprint_nodes_max);
    if (r.tip_radius > 0)
      std::cout << "; tool tip " << r.tip_radius * 1e3 << " mm, its force on up to " << footprint << " surface nodes";
    else
      std::cout << "; a point proxy";
    if (r.local_model != "none")
      std::cout << "; the servo's local contact model (" << r.local_model << " compliance) predicted the next step's "
                << "force within " << r.local_model_error_rms << " N rms, " << r.local_model_error_max << " N at most";
    std::cout << "; device " << r.device;
    if (r.link.received > 0)
      std::cout << ": " << r.link.received << " packets taken, " << r.link.stale << " stale, " << r.link.lost
                << " lost, " << r.link.malformed << " malformed, round trip p50 " << r.link.rtt_p50_us << " us, p99 "
                << r.link.rtt_p99_us << " us";
    if (r.link.faults > 0) std::cout << ", " << r.link.faults << " faults (0 N from the first)";
    std::cout << "; outputs in " << out.string() << "\n";
    if (r.link.silent_cycles > 0)
      std::cerr << "vtb haptics: the device's link fell silent at t = " << r.link.first_silent_time
                << " s: 0 N was sent for " << r.link.silent_cycles << " servo cycles (no state packet for longer than "
                << "the watchdog's " << with_device(scene, o->device).haptics->link_watchdog * 1e3 << " ms)\n";
    if (r.physics_time_ratio < 0.95)
      std::cerr << "vtb haptics: warning: the body ran at " << r.physics_time_ratio
                << "x wall time: its physics step (median " << r.physics_step_median_us
                << " us) did not keep pace with " << r.physics_dt_us
                << " us a step; a coarser mesh or a larger --physics-dt would\n";
    // Timing a user should not miss: late servo cycles mean the force felt was held longer
    // than one period (docs/haptics.md says what lowers them).
    if (r.deadline_misses > 0)
      std::cerr << "vtb haptics: warning: " << r.deadline_misses << " of " << r.samples
                << " servo cycles started more than half a period late (worst period " << r.period_max_us
                << " us); see docs/haptics.md, 'Timing on a loaded machine'\n";
    return 0;
  };
}

} // namespace vtb::cli
