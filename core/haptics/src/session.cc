#include "vtb/haptics/session.hh"

#include "vtb/problem/solver_registry.hh"
#include "vtb/solvers/filter_pick.hh"

#include "physics_side.hh"
#include "realtime_thread.hh"
#include "servo.hh"
#include "vtb/haptics/devices/builtin_devices.hh"
#include "vtb/haptics/devices/plugin_device.hh"
#include "vtb/haptics/devices/udp_device.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/simulation.hh"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <thread>

#include <sys/mman.h>

namespace vtb {
namespace {

using steady = std::chrono::steady_clock;

} // namespace

namespace {

/// The devices: one per probe, each behind the device ABI (plugin_device.hh) but the UDP
/// bridge's: simulated ProCATs held by scripted hands, replays or null devices (vtb's own), or a
/// plug-in or a UDP device (one probe). 3D waypoints are world points, taken to the device's plane.
template <int dim>
std::vector<std::unique_ptr<HapticDevice>> make_devices(const Scene& scene, const HapticsOptions& opt,
                                                        const DevicePlane<dim>& plane, long ticks) {
  const std::string file = scene.file.string();
  const HapticsDesc& h = *scene.haptics;
  DeviceSpec spec;
  spec.max_force = h.max_force;
  spec.rate_hz = h.rate;
  std::vector<std::unique_ptr<HapticDevice>> devices;
  const int probes = 1 + static_cast<int>(h.probes.size());
  const auto builtin = [&](const char* name, const std::string& config) {
    devices.push_back(std::make_unique<PluginDevice>(builtin_device_api(name), name, config, spec));
  };
  if ((h.device == "plugin" || h.device == "udp") && probes > 1)
    throw InputError(file + ": [haptics].device = \"" + h.device +
                     "\" drives one probe; [[haptics.probe]] adds simulated devices only");
  if (h.device == "plugin") {
    devices.push_back(PluginDevice::load(h.plugin, h.plugin_config, spec));
    return devices;
  }
  if (h.device == "udp") {
    if (opt.lockstep)
      throw InputError(file + ": [haptics].device = \"udp\" runs in real time (a device in another process has its "
                              "own clock); drop --lockstep");
    UdpDevice::Options o;
    o.endpoint = parse_endpoint(h.address, file + ": [haptics].address");
    o.watchdog = h.link_watchdog;
    o.max_samples = ticks + 2;
    devices.push_back(std::make_unique<UdpDevice>(spec, o));
    return devices;
  }
  if (h.device == "null") {
    for (int i = 0; i < probes; ++i) builtin("null", null_config(spec.workspace_max)); // out of reach
    return devices;
  }
  if (h.device == "replay") {
    if (opt.replay.empty()) throw InputError(file + ": [haptics].device = \"replay\" needs --replay FILE");
    for (int i = 0; i < probes; ++i) builtin("replay", replay_config(spec, opt.replay, i));
    return devices;
  }
  if (!h.hand) throw InputError(file + ": [haptics.hand] is missing: the simulated ProCAT needs a scripted hand");
  for (int i = 0; i < probes; ++i) {
    const HandDesc& desc = i == 0 ? *h.hand : h.probes[static_cast<std::size_t>(i - 1)];
    HandScript hand;
    for (const auto& w : desc.waypoints) {
      if (w.size() == 2) {
        hand.waypoints.emplace_back(w[0], w[1]);
      } else if constexpr (dim == 3) {
        hand.waypoints.emplace_back(plane.axes.transpose() * (Eigen::Vector3d(w[0], w[1], w[2]) - plane.origin));
      } else {
        throw InputError(file + ": [haptics] waypoints of " +
                         (i == 0 ? std::string("[haptics.hand]") : "[[haptics.probe]] #" + std::to_string(i)) +
                         " are [x, y, z]; this mesh is 2D");
      }
    }
    hand.duration = desc.duration;
    hand.grip_stiffness = desc.grip_stiffness;
    builtin("procat-sim", procat_sim_config(spec, hand));
  }
  return devices;
}

/// The servo loop's own timing, whichever way it ran.
struct LoopTiming {
  std::vector<double> periods, tick_us; ///< each cycle's period and its own work, us
  long misses = 0;                      ///< cycles that started more than half a period late
  std::vector<std::string> setup;       ///< what the real-time servo thread was granted
  double time_ratio = 1;                ///< simulated time the physics reached over wall time (at most 1)
};

/// A coupling stiffer than the device renders stably is limited to its maximum, as a device
/// driver does; `notes` says so.
HapticsDesc limited_coupling(const Scene& scene, double k_max, std::vector<std::string>& notes) {
  HapticsDesc h = *scene.haptics;
  if (h.coupling_stiffness > k_max) {
    std::ostringstream msg;
    msg << scene.file.string() << ": [haptics].coupling_stiffness = " << h.coupling_stiffness
        << " N/m exceeds the stiffness the ProCAT renders stably; limited to " << k_max << " N/m";
    notes.push_back(msg.str());
    h.coupling_stiffness = k_max;
  }
  return h;
}

/// The physics' solver options for a session. Its dt: --physics-dt; else the scene's `[solver]
/// dt` where it names one; else, in real time, the rate the body affords (with_physics_rate:
/// the most accurate filter whose measured step, with headroom, fits a whole number of servo
/// periods), and in lockstep the servo's period. Its step budget: the scene's, else its dt;
/// `auto` then picks within it (with_budget_pick) where with_physics_rate has not.
template <int dim>
IntegratorOptions physics_options(const Scene& scene, const Model<dim>& model, const HapticsOptions& opt,
                                  double period) {
  IntegratorOptions o = integrator_options(scene.solver);
  if (opt.physics_dt > 0) {
    o.dt = opt.physics_dt;
  } else if (!scene.solver.dt_given && !(o.step_budget > 0)) {
    if (opt.lockstep)
      o.dt = period;
    else
      o = with_physics_rate(model, o, period,
                            TrialCoupling{scene.haptics->coupling_stiffness, scene.haptics->coupling_damping});
  }
  if (!(o.step_budget > 0)) o.step_budget = o.dt;
  return with_budget_pick(model, o);
}

/// Simulated time only: servo and physics interleaved, deterministic (tests and replays).
template <int dim, class Advance>
LoopTiming run_lockstep(Servo<dim>& servo, Physics<dim>& physics, long ticks, double period, Advance advance_devices) {
  LoopTiming lt;
  lt.periods.reserve(static_cast<std::size_t>(ticks));
  for (long k = 0; k < ticks; ++k) {
    const double t = static_cast<double>(k) * period;
    while (physics.time() + 1e-12 < t)
      if (!physics.step()) break;
    servo.tick(t);
    advance_devices(period);
    lt.periods.push_back(period * 1e6);
  }
  return lt;
}

/// Real time: the servo on its own thread at absolute deadlines (the last 200 us spun), the
/// physics on this one paced to wall time.
template <int dim, class Advance>
LoopTiming run_realtime(Servo<dim>& servo, Physics<dim>& physics, long ticks, double period, const HapticsOptions& opt,
                        Advance advance_devices) {
  LoopTiming lt;
  lt.periods.reserve(static_cast<std::size_t>(ticks));
  lt.tick_us.reserve(static_cast<std::size_t>(ticks));
  std::atomic<bool> done{false};
  if (opt.lock_memory) lt.setup.push_back(mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? "mlock" : "mlock-denied");
  if (opt.pin_cpu >= 0) keep_off_cpu(opt.pin_cpu); // the physics (this thread) leaves the servo's core
  const auto start = steady::now() + std::chrono::milliseconds(5);
  std::thread servo_thread([&] {
    for (auto& g : set_up_servo_thread(opt)) lt.setup.push_back(std::move(g));
    auto next = start;
    auto last = start;
    const auto p = std::chrono::duration_cast<steady::duration>(std::chrono::duration<double>(period));
    for (long k = 0; k < ticks; ++k) {
      std::this_thread::sleep_until(next - std::chrono::microseconds(200));
      while (steady::now() < next) {
      }
      const auto now = steady::now();
      if (now - next > p / 2) ++lt.misses;
      if (k > 0) lt.periods.push_back(std::chrono::duration<double, std::micro>(now - last).count());
      last = now;
      servo.tick(static_cast<double>(k) * period);
      lt.tick_us.push_back(std::chrono::duration<double, std::micro>(steady::now() - now).count());
      advance_devices(period);
      next += p;
      if (now - next > 10 * p) next = now + p; // far behind: resynchronise rather than burst
    }
    done = true;
  });
  while (!done) {
    const auto target =
        start + std::chrono::duration_cast<steady::duration>(std::chrono::duration<double>(physics.time()));
    std::this_thread::sleep_until(target);
    if (!physics.step()) {
      while (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      break;
    }
  }
  servo_thread.join();
  const double wall = std::chrono::duration<double>(steady::now() - start).count();
  lt.time_ratio = wall > 0 ? std::min(1.0, physics.time() / wall) : 1.0;
  if (opt.lock_memory) munlockall();
  return lt;
}

/// The servo's report completed with the totals over probes and the loop's timing.
template <int dim>
HapticsReport finish_report(HapticsReport rep, LoopTiming lt, const Physics<dim>& physics, bool lockstep) {
  rep.dim = dim;
  rep.realtime_setup = std::move(lt.setup);
  rep.samples = static_cast<long>(rep.t.size());
  for (const ProbeTrace& p : rep.probes) {
    rep.max_force = std::max(rep.max_force, p.max_force);
    rep.saturated_samples += p.saturated_samples;
    rep.nonfinite_samples += p.nonfinite_samples;
    rep.energy_to_user += p.energy_to_user;
  }
  rep.period_max_us = lt.periods.empty() ? 0 : *std::max_element(lt.periods.begin(), lt.periods.end());
  if (!lockstep) rep.period_us = lt.periods;
  const StepStats cycle = step_stats(std::move(lt.periods)), tick = step_stats(std::move(lt.tick_us));
  rep.rate_hz_mean = cycle.mean > 0 ? 1e6 / cycle.mean : 0.0;
  rep.period_p99_us = cycle.p99;
  rep.deadline_misses = lt.misses;
  rep.tick_median_us = tick.median;
  rep.tick_p99_us = tick.p99;
  rep.physics_time_ratio = lt.time_ratio;
  rep.physics_dt_us = physics.dt() * 1e6;
  rep.local_model = physics.compliance_source();
  rep.physics_steps = static_cast<long>(physics.step_times().size());
  rep.physics_step_median_us = step_stats(physics.step_times()).median;
  rep.physics_step_max_us =
      physics.step_times().empty() ? 0.0 : *std::max_element(physics.step_times().begin(), physics.step_times().end());
  return rep;
}

template <int dim> HapticsReport run_session(const Scene& scene, const HapticsOptions& opt, const Model<dim>& model) {
  const DevicePlane<dim> plane = device_plane(scene, model.mesh);
  const long ticks = std::lround(scene.duration / (1.0 / scene.haptics->rate));
  std::vector<std::unique_ptr<HapticDevice>> devices = make_devices(scene, opt, plane, ticks);
  std::vector<std::string> notes;
  const HapticsDesc h = limited_coupling(scene, devices.front()->spec().max_stiffness, notes);
  // The physics of a session steps at a fixed dt, one step between servo updates.
  if (!solvers::is_stepper(solvers::find(scene.solver.kind)))
    throw InputError(scene.file.string() + ": [solver].kind = \"" + scene.solver.kind +
                     "\": a haptics session needs a fixed-step spring solver (" + solvers::list(solvers::is_stepper) +
                     ")");
  const double period = 1.0 / h.rate;
  const IntegratorOptions o = physics_options(scene, model, opt, period);

  Snapshot<dim> init;
  init.x = model.net.rest;
  init.v = Nodal<dim>::Zero(dim, model.num_nodes());
  init.models.resize(devices.size());
  TripleBuffer<Snapshot<dim>> snap(init);
  TripleBuffer<Commands<dim>> cmd(Commands<dim>(devices.size()));
  Servo<dim> servo(devices, model.mesh, scene.material, h, plane, ticks + 2, o.dt, snap, cmd);
  const double fallback =
      half_space_tip_compliance(dim, scene.material.young_modulus, scene.material.poisson_ratio, h.tip_radius_for(dim));
  Physics<dim> physics(model, o, snap, cmd, h, opt, period, fallback);
  const auto advance_devices = [&devices](double dt) {
    for (auto& d : devices) d->advance(dt);
  };
  const double servo_tip_edge = servo.tip().mean_edge();
  // In real time the physics builds the contact trees the servo adopts (no build in a servo
  // cycle while it keeps up); lockstep keeps the builds in the servo (outputs as before).
  if (!opt.lockstep) physics.build_contact_trees_for(servo.contacts());
  LoopTiming lt = opt.lockstep ? run_lockstep(servo, physics, ticks, period, advance_devices)
                               : run_realtime(servo, physics, ticks, period, opt, advance_devices);
  HapticsReport rep = finish_report(std::move(servo.report()), std::move(lt), physics, opt.lockstep);
  rep.local_model_error_rms = servo.prediction_error_rms();
  rep.local_model_error_max = servo.prediction_error_max();
  if constexpr (dim == 3) {
    rep.contact_tree_builds_physics = servo.contacts().tree().prepared();
    rep.contact_tree_builds_servo = servo.contacts().tree().builds();
  }
  rep.device = devices.front()->name();
  for (const auto& d : devices) {
    const DeviceLinkStats l = d->link_stats();
    rep.link.received += l.received;
    rep.link.stale += l.stale;
    rep.link.lost += l.lost;
    rep.link.malformed += l.malformed;
    rep.link.faults += l.faults;
    rep.link.silent_cycles += l.silent_cycles;
    if (l.first_silent_time >= 0 &&
        (rep.link.first_silent_time < 0 || l.first_silent_time < rep.link.first_silent_time))
      rep.link.first_silent_time = l.first_silent_time;
    rep.link.rtt_p50_us = std::max(rep.link.rtt_p50_us, l.rtt_p50_us);
    rep.link.rtt_p99_us = std::max(rep.link.rtt_p99_us, l.rtt_p99_us);
  }
  rep.coupling_stiffness = h.coupling_stiffness;
  rep.tip_radius = h.tip_radius_for(dim);
  rep.surface_mean_edge = servo_tip_edge;
  for (std::size_t i = 0; i < rep.probes.size(); ++i) {
    const ProbeTrace& p = rep.probes[i];
    if (rep.tip_radius > 0 && p.unresolved_samples > 0) {
      std::ostringstream msg;
      msg << scene.file.string() << ": [haptics].tip_radius = " << rep.tip_radius * 1e3
          << " mm is narrower than the facets it touched in " << p.unresolved_samples << " of " << p.contact_samples
          << " contact cycles of probe " << i << " (mean surface edge " << rep.surface_mean_edge * 1e3
          << " mm): the mesh does not resolve the tip there, and the force rests on the local compliance added in "
             "series "
             "(the half-space's, docs/haptics.md)";
      notes.push_back(msg.str());
    }
    if (p.truncated_samples > 0)
      notes.push_back(scene.file.string() + ": the tip of probe " + std::to_string(i) + " covered more than " +
                      std::to_string(Footprint::kMaxNodes) + " surface nodes in " +
                      std::to_string(p.truncated_samples) + " cycles; the nodes beyond took no share of its force");
  }
  rep.physics_step_budget_us = o.step_budget * 1e6;
  rep.physics_steps_over_budget = std::count_if(physics.step_times().begin(), physics.step_times().end(),
                                                [&](double us) { return us > rep.physics_step_budget_us; });
  if (o.kind == solvers::kFiltered) rep.physics_filter = chosen_filter(model, o.filter);
  rep.physics_filter_reason = o.filter_reason;
  rep.springs = model.net.calibration;
  if (!model.net.calibration_note.empty()) notes.push_back(model.net.calibration_note);
  rep.notes = std::move(notes);
  return rep;
}

} // namespace

Scene with_device(const Scene& scene, const std::string& device) {
  if (device.empty()) return scene;
  Scene s = scene;
  HapticsDesc& h = *s.haptics;
  if (device.rfind("plugin:", 0) == 0) {
    h.device = "plugin";
    h.plugin = device.substr(7);
    if (h.plugin.empty()) throw InputError("--device plugin:PATH: the path is empty");
  } else if (device.rfind("udp:", 0) == 0) {
    h.device = "udp";
    h.address = device.substr(4);
  } else if (device == "procat-sim" || device == "replay" || device == "null") {
    h.device = device;
  } else {
    throw InputError("--device " + device + ": expected procat-sim, replay, null, plugin:PATH or udp:HOST:PORT");
  }
  return s;
}

HapticsReport run_haptics(const Scene& scene, const HapticsOptions& opt) {
  if (!scene.haptics)
    throw InputError(scene.file.string() + ": [haptics] is missing: this scene does not use the device");
  const Scene s = with_device(scene, opt.device);
  return with_model(
      s, [&](const auto& model) { return run_session(s, opt, model); }, {}, opt.yardstick);
}

} // namespace vtb
