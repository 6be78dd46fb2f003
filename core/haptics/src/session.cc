#include "vtb/haptics/session.hh"

#include "vtb/problem/solver_registry.hh"
#include "vtb/solvers/filter_pick.hh"

#include "realtime_thread.hh"
#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/coupling.hh"
#include "vtb/haptics/device.hh"
#include "vtb/haptics/device_plane.hh"
#include "vtb/haptics/force_shaping.hh"
#include "vtb/haptics/triple_buffer.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/integrator.hh"
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

template <int dim> using Vec = Eigen::Matrix<double, dim, 1>;

/// What the physics publishes for the servo: the deformed body and when.
template <int dim> struct Snapshot {
  double t = 0;
  bool finite = true;
  Nodal<dim> x, v;
};

/// What the servo sends back for one probe: the contact force on the body, where (no nodes:
/// not touching).
template <int dim> struct ContactCommand {
  Footprint footprint;
  Vec<dim> force_on_body = Vec<dim>::Zero();
};
template <int dim> using Commands = std::vector<ContactCommand<dim>>; ///< one per probe, sized once

/// The servo side: devices, proxies, coupling, shaping, log. No allocation in tick().
template <int dim> class Servo {
public:
  Servo(std::vector<std::unique_ptr<HapticDevice>>& devices, const Mesh<dim>& mesh, const MaterialDesc& material,
        const HapticsDesc& h, const DevicePlane<dim>& plane, long max_samples, TripleBuffer<Snapshot<dim>>& snap,
        TripleBuffer<Commands<dim>>& cmd)
      : m_devices(devices), m_contacts(mesh, devices.size(), h.tip_radius_for(dim), material), m_h(h), m_plane(plane),
        m_snap(snap), m_cmd(cmd), m_x(mesh.points), m_max(max_samples) {
    m_rep.t.reserve(static_cast<std::size_t>(max_samples));
    m_rep.probes.resize(devices.size());
    for (std::size_t i = 0; i < devices.size(); ++i) {
      m_shapers.emplace_back(
          typename BasicForceShaper<dim>::Params{std::min(h.max_force, devices[i]->spec().max_force), 0.5, 0.03, 0.01});
      for (auto* v : {&m_rep.probes[i].hx, &m_rep.probes[i].hy, &m_rep.probes[i].fx, &m_rep.probes[i].fy})
        v->reserve(static_cast<std::size_t>(max_samples));
    }
  }

  /// One servo cycle at servo time t, for every probe.
  void tick(double t) {
    const bool fresh = m_snap.fetch();
    const Snapshot<dim>& s = m_snap.front();
    // Local linear model of the body between physics updates: nodes move on with their
    // velocity since the snapshot (refreshed by every physics step).
    const double age = std::clamp(t - s.t, 0.0, 0.05);
    m_x = s.x + age * s.v;
    const bool finite = s.finite && m_x.allFinite();
    if (fresh && finite) m_contacts.refit(s.x);
    const bool record = static_cast<long>(m_rep.t.size()) < m_max;
    if (record) m_rep.t.push_back(t);
    bool all_zero = true;
    Commands<dim>& out = m_cmd.back();
    for (std::size_t i = 0; i < m_devices.size(); ++i) {
      Eigen::Vector2d pos, vel;
      m_devices[i]->read(pos, vel);
      const Vec<dim> handle = m_plane.origin + m_plane.axes * pos;
      Vec<dim> raw = Vec<dim>::Zero();
      ContactResult<dim> c;
      if (finite) c = m_contacts.update(i, handle, m_x);
      if (c.touching) raw = coupling(c, handle, m_plane.axes * vel, s.v);
      // The coupling force is shaped whole; a planar device renders its in-plane part (the
      // rest is taken by its mechanism), the body receives the whole reaction.
      const Vec<dim> f = m_shapers[i].shape(raw, t, s.t, finite);
      const Eigen::Vector2d fd = m_plane.axes.transpose() * f;
      m_devices[i]->command(fd);
      out[i].footprint = c.touching ? c.footprint : Footprint{};
      out[i].force_on_body = -f;
      if (c.touching) count_footprint(m_rep.probes[i], c.footprint);
      all_zero = all_zero && f.norm() == 0.0;
      if (record) log(m_rep.probes[i], m_shapers[i], pos, vel, fd);
      if (m_shapers[i].faulted() && m_rep.fault_time < 0) m_rep.fault_time = m_shapers[i].fault_time();
    }
    m_cmd.publish();
    if (m_rep.fault_time >= 0 && m_rep.force_zero_time < 0 && all_zero) m_rep.force_zero_time = t;
  }

  HapticsReport& report() { return m_rep; }
  const TipFootprint<dim>& tip() const { return m_contacts.tip(); }

private:
  Vec<dim> coupling(const ContactResult<dim>& c, const Vec<dim>& handle, const Vec<dim>& handle_velocity,
                    const Nodal<dim>& node_velocity) const {
    return virtual_coupling<dim>(c, handle, handle_velocity, node_velocity, m_h.coupling_stiffness,
                                 m_h.coupling_damping);
  }

  /// The tip's footprint over the cycles in contact: its largest node count, the cycles where
  /// the tip was narrower than the touched facet (not resolved) or covered too many nodes.
  static void count_footprint(ProbeTrace& p, const Footprint& fp) {
    ++p.contact_samples;
    p.footprint_nodes_max = std::max(p.footprint_nodes_max, fp.count);
    p.unresolved_samples += !fp.resolved;
    p.truncated_samples += fp.truncated;
  }

  void log(ProbeTrace& p, const BasicForceShaper<dim>& shaper, const Eigen::Vector2d& pos, const Eigen::Vector2d& vel,
           const Eigen::Vector2d& f) {
    const std::size_t n = m_rep.t.size();
    if (n > 1) p.energy_to_user += f.dot(vel) * (m_rep.t[n - 1] - m_rep.t[n - 2]);
    p.hx.push_back(pos.x());
    p.hy.push_back(pos.y());
    p.fx.push_back(f.x());
    p.fy.push_back(f.y());
    if (!f.allFinite()) ++p.nonfinite_samples;
    if (shaper.last_saturated()) ++p.saturated_samples;
    p.max_force = std::max(p.max_force, f.norm());
  }

  std::vector<std::unique_ptr<HapticDevice>>& m_devices;
  Contacts<dim> m_contacts;
  const HapticsDesc& m_h;
  DevicePlane<dim> m_plane;
  std::vector<BasicForceShaper<dim>> m_shapers;
  TripleBuffer<Snapshot<dim>>& m_snap;
  TripleBuffer<Commands<dim>>& m_cmd;
  Nodal<dim> m_x;
  HapticsReport m_rep;
  long m_max = 0;
};

/// The physics side: one spring-solver step with the probes' contact forces applied, then publish.
template <int dim> class Physics {
public:
  Physics(const Model<dim>& model, const IntegratorOptions& o, TripleBuffer<Snapshot<dim>>& snap,
          TripleBuffer<Commands<dim>>& cmd, const HapticsDesc& h, const HapticsOptions& faults)
      : m_model(model), m_integ(make_integrator(model, o)), m_state(initial_state(model)), m_snap(snap), m_cmd(cmd),
        m_k(h.coupling_stiffness), m_b(h.coupling_damping), m_faults(faults) {
    m_state.applied = Nodal<dim>::Zero(dim, model.num_nodes());
    m_state.applied_stiffness = Eigen::VectorXd::Zero(model.num_nodes());
    m_state.applied_damping = Eigen::VectorXd::Zero(model.num_nodes());
    m_state.applied_group = Eigen::VectorXi::Constant(model.num_nodes(), -1);
  }

  double dt() const { return m_integ->dt(); }
  double time() const { return m_state.t; }

  /// Steps once; false when a stall fault has stopped the physics.
  bool step() {
    using F = HapticsOptions::Fault;
    if (m_faults.fault == F::stall && m_state.t >= m_faults.fault_time) return false;
    m_cmd.fetch();
    m_state.applied.setZero();
    m_state.applied_stiffness.setZero();
    m_state.applied_damping.setZero();
    m_state.applied_group.setConstant(-1);
    // Each probe's force on its footprint's nodes by their weights, and the coupling's
    // stiffness and damping with it, one group per probe, for the integrators that solve them
    // implicitly: the proxy is sum_k w_k x_k along the tip's normal, so the coupling's k acts as
    // k w w^T (coupling_set.hh). Explicitly, a 400 N/m coupling on a node of 0.04 g is beyond
    // the step's limit at dt = 1 ms (sqrt(m/k) = 0.33 ms).
    int group = 0;
    for (const ContactCommand<dim>& c : m_cmd.front()) {
      if (c.footprint.count > 0) apply_to_body<dim>(c.footprint, c.force_on_body, m_k, m_b, group, m_state);
      ++group;
    }
    const auto a = steady::now();
    m_integ->step(m_state);
    m_step_us.push_back(std::chrono::duration<double, std::micro>(steady::now() - a).count());
    Snapshot<dim>& s = m_snap.back();
    s.t = m_state.t;
    s.x = m_model.net.rest + m_state.u;
    s.v = m_state.v;
    if (m_faults.fault == F::nan && m_state.t >= m_faults.fault_time)
      s.x.setConstant(std::numeric_limits<double>::quiet_NaN());
    s.finite = s.x.allFinite() && s.v.allFinite() && max_strain(m_model.net, m_state.u) < 10.0;
    m_snap.publish();
    return true;
  }

  const std::vector<double>& step_times() const { return m_step_us; }

private:
  const Model<dim>& m_model;
  std::unique_ptr<Integrator<dim>> m_integ;
  State<dim> m_state;
  TripleBuffer<Snapshot<dim>>& m_snap;
  TripleBuffer<Commands<dim>>& m_cmd;
  double m_k, m_b; ///< the virtual coupling's stiffness and damping
  HapticsOptions m_faults;
  std::vector<double> m_step_us;
};

} // namespace

namespace {

/// The devices: one per probe, all simulated ProCATs held by scripted hands, or all replays.
/// 3D waypoints are world points, taken to the device's plane.
template <int dim>
std::vector<std::unique_ptr<HapticDevice>> make_devices(const Scene& scene, const HapticsOptions& opt,
                                                        const DevicePlane<dim>& plane) {
  const std::string file = scene.file.string();
  const HapticsDesc& h = *scene.haptics;
  DeviceSpec spec;
  spec.max_force = h.max_force;
  spec.rate_hz = h.rate;
  std::vector<std::unique_ptr<HapticDevice>> devices;
  const int probes = 1 + static_cast<int>(h.probes.size());
  if (h.device == "replay") {
    if (opt.replay.empty()) throw InputError(file + ": [haptics].device = \"replay\" needs --replay FILE");
    for (int i = 0; i < probes; ++i) devices.push_back(std::make_unique<ReplayDevice>(spec, opt.replay, i));
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
    devices.push_back(std::make_unique<SimulatedProCAT>(spec, hand));
  }
  return devices;
}

/// The servo loop's own timing, whichever way it ran.
struct LoopTiming {
  std::vector<double> periods, tick_us; ///< each cycle's period and its own work, us
  long misses = 0;                      ///< cycles that started more than half a period late
  std::vector<std::string> setup;       ///< what the real-time servo thread was granted
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
  rep.physics_steps = static_cast<long>(physics.step_times().size());
  rep.physics_step_median_us = step_stats(physics.step_times()).median;
  return rep;
}

template <int dim> HapticsReport run_session(const Scene& scene, const HapticsOptions& opt, const Model<dim>& model) {
  const DevicePlane<dim> plane = device_plane(scene, model.mesh);
  std::vector<std::unique_ptr<HapticDevice>> devices = make_devices(scene, opt, plane);
  std::vector<std::string> notes;
  const HapticsDesc h = limited_coupling(scene, devices.front()->spec().max_stiffness, notes);
  // The physics of a session steps at a fixed dt, one step between servo updates.
  if (!solvers::is_stepper(solvers::find(scene.solver.kind)))
    throw InputError(scene.file.string() + ": [solver].kind = \"" + scene.solver.kind +
                     "\": a haptics session needs a fixed-step spring solver (" + solvers::list(solvers::is_stepper) +
                     ")");
  IntegratorOptions o = integrator_options(scene.solver);
  // The physics steps once per servo cycle: its budget is the cycle's period unless the scene
  // sets one, and auto picks the most accurate filter that fits it (filter_pick.hh).
  if (!(o.step_budget > 0)) o.step_budget = 1.0 / h.rate;
  o = with_budget_pick(model, o);

  Snapshot<dim> init;
  init.x = model.net.rest;
  init.v = Nodal<dim>::Zero(dim, model.num_nodes());
  TripleBuffer<Snapshot<dim>> snap(init);
  TripleBuffer<Commands<dim>> cmd(Commands<dim>(devices.size()));
  const double period = 1.0 / h.rate;
  const long ticks = std::lround(scene.duration / period);
  Servo<dim> servo(devices, model.mesh, scene.material, h, plane, ticks + 2, snap, cmd);
  Physics<dim> physics(model, o, snap, cmd, h, opt);
  const auto advance_devices = [&devices](double dt) {
    for (auto& d : devices) d->advance(dt);
  };
  const double servo_tip_edge = servo.tip().mean_edge();
  LoopTiming lt = opt.lockstep ? run_lockstep(servo, physics, ticks, period, advance_devices)
                               : run_realtime(servo, physics, ticks, period, opt, advance_devices);
  HapticsReport rep = finish_report(std::move(servo.report()), std::move(lt), physics, opt.lockstep);
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
  rep.notes = std::move(notes);
  return rep;
}

} // namespace

HapticsReport run_haptics(const Scene& scene, const HapticsOptions& opt) {
  if (!scene.haptics)
    throw InputError(scene.file.string() + ": [haptics] is missing: this scene does not use the device");
  return with_model(
      scene, [&](const auto& model) { return run_session(scene, opt, model); }, {}, opt.yardstick);
}

} // namespace vtb
