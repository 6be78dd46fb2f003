#include "vtb/core/haptics/session.hh"

#include "vtb/core/haptics/contact2d.hh"
#include "vtb/core/haptics/device.hh"
#include "vtb/core/haptics/force_shaping.hh"
#include "vtb/core/haptics/triple_buffer.hh"
#include "vtb/core/integrator.hh"
#include "vtb/core/simulation.hh"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>
#include <thread>

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

namespace vtb {
namespace {

using steady = std::chrono::steady_clock;

/// What the physics publishes for the servo: the deformed body and when.
struct Snapshot {
  double t = 0;
  bool finite = true;
  Nodal<2> x, v;
};

/// What the servo sends back: the contact force on the body, where.
struct ContactCommand {
  int edge = -1;
  double along = 0;
  Eigen::Vector2d force_on_body = Eigen::Vector2d::Zero();
};

/// The servo side: device, proxy, coupling, shaping, log. No allocation in tick().
class Servo {
public:
  Servo(HapticDevice& device, const Mesh2& mesh, const HapticsDesc& h, long max_samples, TripleBuffer<Snapshot>& snap,
        TripleBuffer<ContactCommand>& cmd)
      : m_device(device), m_contact(mesh), m_h(h),
        m_shaper(ForceShaper::Params{std::min(h.max_force, device.spec().max_force), 0.5, 0.03, 0.01}), m_snap(snap),
        m_cmd(cmd), m_x(mesh.points) {
    for (auto* v : {&m_rep.t, &m_rep.hx, &m_rep.hy, &m_rep.fx, &m_rep.fy})
      v->reserve(static_cast<std::size_t>(max_samples));
    m_max = max_samples;
  }

  /// One servo cycle at servo time t.
  void tick(double t) {
    Eigen::Vector2d pos, vel;
    m_device.read(pos, vel);
    m_snap.fetch();
    const Snapshot& s = m_snap.front();
    // Local linear model of the body between physics updates: nodes move on with their
    // velocity since the snapshot (refreshed by every physics step).
    const double age = std::clamp(t - s.t, 0.0, 0.05);
    m_x = s.x + age * s.v;
    Eigen::Vector2d raw = Eigen::Vector2d::Zero();
    const BoundaryContact::Result c = m_contact.update(pos, m_x);
    if (c.touching) raw = m_h.coupling_stiffness * (c.proxy - pos) - m_h.coupling_damping * vel;
    const Eigen::Vector2d f = m_shaper.shape(raw, t, s.t, s.finite && m_x.allFinite());
    m_device.command(f);
    ContactCommand& out = m_cmd.back();
    out.edge = c.touching ? c.edge : -1;
    out.along = c.along;
    out.force_on_body = -f;
    m_cmd.publish();
    record(t, pos, vel, f);
  }

  HapticsReport& report() { return m_rep; }
  const BoundaryContact& contact() const { return m_contact; }
  const ForceShaper& shaper() const { return m_shaper; }

private:
  void record(double t, const Eigen::Vector2d& pos, const Eigen::Vector2d& vel, const Eigen::Vector2d& f) {
    if (static_cast<long>(m_rep.t.size()) >= m_max) return;
    m_rep.t.push_back(t);
    m_rep.hx.push_back(pos.x());
    m_rep.hy.push_back(pos.y());
    m_rep.fx.push_back(f.x());
    m_rep.fy.push_back(f.y());
    if (!f.allFinite()) ++m_rep.nonfinite_samples;
    if (m_shaper.last_saturated()) ++m_rep.saturated_samples;
    m_rep.max_force = std::max(m_rep.max_force, f.norm());
    if (!m_rep.t.empty() && m_rep.t.size() > 1) m_rep.energy_to_user += f.dot(vel) * (t - m_rep.t[m_rep.t.size() - 2]);
    if (m_shaper.faulted() && m_rep.fault_time < 0) m_rep.fault_time = m_shaper.fault_time();
    if (m_shaper.faulted() && m_rep.force_zero_time < 0 && f.norm() == 0.0) m_rep.force_zero_time = t;
  }

  HapticDevice& m_device;
  BoundaryContact m_contact;
  const HapticsDesc& m_h;
  ForceShaper m_shaper;
  TripleBuffer<Snapshot>& m_snap;
  TripleBuffer<ContactCommand>& m_cmd;
  Nodal<2> m_x;
  HapticsReport m_rep;
  long m_max = 0;
};

/// The physics side: one spring-solver step with the contact force applied, then publish.
class Physics {
public:
  Physics(const Model<2>& model, const IntegratorOptions& o, TripleBuffer<Snapshot>& snap,
          TripleBuffer<ContactCommand>& cmd, const std::vector<std::array<int, 2>>& edges, const HapticsOptions& faults)
      : m_model(model), m_integ(make_integrator(model, o)), m_state(initial_state(model)), m_snap(snap), m_cmd(cmd),
        m_edges(edges), m_faults(faults) {
    m_state.applied = Nodal<2>::Zero(2, model.num_nodes());
  }

  double dt() const { return m_integ->dt(); }
  double time() const { return m_state.t; }

  /// Steps once; false when a stall fault has stopped the physics.
  bool step() {
    using F = HapticsOptions::Fault;
    if (m_faults.fault == F::stall && m_state.t >= m_faults.fault_time) return false;
    m_cmd.fetch();
    const ContactCommand& c = m_cmd.front();
    m_state.applied.setZero();
    if (c.edge >= 0) {
      const auto& e = m_edges[static_cast<std::size_t>(c.edge)];
      m_state.applied.col(e[0]) += (1 - c.along) * c.force_on_body;
      m_state.applied.col(e[1]) += c.along * c.force_on_body;
    }
    const auto a = steady::now();
    m_integ->step(m_state);
    m_step_us.push_back(std::chrono::duration<double, std::micro>(steady::now() - a).count());
    Snapshot& s = m_snap.back();
    s.t = m_state.t;
    s.x = m_model.net.rest + m_state.u;
    s.v = m_state.v;
    if (m_faults.fault == F::nan && m_state.t >= m_faults.fault_time)
      s.x.setConstant(std::numeric_limits<double>::quiet_NaN());
    s.finite = s.x.allFinite() && s.v.allFinite() && max_strain(m_model.net, m_state.u) < 10.0;
    m_snap.publish();
    return true;
  }

  std::vector<double>& step_times() { return m_step_us; }

private:
  const Model<2>& m_model;
  std::unique_ptr<Integrator<2>> m_integ;
  State<2> m_state;
  TripleBuffer<Snapshot>& m_snap;
  TripleBuffer<ContactCommand>& m_cmd;
  const std::vector<std::array<int, 2>>& m_edges;
  HapticsOptions m_faults;
  std::vector<double> m_step_us;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k =
      static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size() - 1), q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

} // namespace

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

HapticsReport run_haptics(const Scene& scene, const HapticsOptions& opt) {
  const std::string file = scene.file.string();
  if (!scene.haptics) throw InputError(file + ": [haptics] is missing: this scene does not use the device");
  const HapticsDesc& h = *scene.haptics;
  AnyMesh any = load_mesh(scene);
  if (!std::holds_alternative<Mesh2>(any))
    throw InputError(file + ": the ProCAT is a 2-DOF planar device; [haptics] needs a 2D mesh");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(std::move(any)));

  DeviceSpec spec;
  spec.max_force = h.max_force;
  spec.rate_hz = h.rate;
  std::unique_ptr<HapticDevice> device;
  if (h.device == "replay") {
    if (opt.replay.empty()) throw InputError(file + ": [haptics].device = \"replay\" needs --replay FILE");
    device = std::make_unique<ReplayDevice>(spec, opt.replay);
  } else {
    if (!h.hand) throw InputError(file + ": [haptics.hand] is missing: the simulated ProCAT needs a scripted hand");
    HandScript hand;
    for (const auto& w : h.hand->waypoints) hand.waypoints.emplace_back(w[0], w[1]);
    hand.duration = h.hand->duration;
    hand.grip_stiffness = h.hand->grip_stiffness;
    device = std::make_unique<SimulatedProCAT>(spec, hand);
  }

  IntegratorOptions o = integrator_options(scene.solver);
  // The physics of a session steps at a fixed dt: CVODE and the FEM fall back to the filter.
  if (o.kind == "cvode" || o.kind == "fem") o.kind = "filtered";

  Snapshot init;
  init.x = model.net.rest;
  init.v = Nodal<2>::Zero(2, model.num_nodes());
  TripleBuffer<Snapshot> snap(init);
  TripleBuffer<ContactCommand> cmd(ContactCommand{});
  const double period = 1.0 / h.rate;
  const long ticks = std::lround(scene.duration / period);
  Servo servo(*device, model.mesh, h, ticks + 2, snap, cmd);
  Physics physics(model, o, snap, cmd, servo.contact().edges(), opt);

  std::vector<double> periods;
  periods.reserve(static_cast<std::size_t>(ticks));
  long misses = 0;
  double elapsed = 0;
  if (opt.lockstep) {
    // Simulated time only: deterministic, for tests and replays.
    for (long k = 0; k < ticks; ++k) {
      const double t = static_cast<double>(k) * period;
      while (physics.time() + 1e-12 < t)
        if (!physics.step()) break;
      servo.tick(t);
      device->advance(period);
      periods.push_back(period * 1e6);
    }
    elapsed = static_cast<double>(ticks) * period;
  } else {
    // Real time: the servo on its own thread, absolute deadlines, the last 200 us spun.
    std::atomic<bool> done{false};
    const auto start = steady::now() + std::chrono::milliseconds(5);
    std::thread servo_thread([&] {
      // A servo loop wants a real-time priority; granted to root (or CAP_SYS_NICE), else it
      // runs as an ordinary thread and the summary's misses tell.
      sched_param prio{};
      prio.sched_priority = 80;
      pthread_setschedparam(pthread_self(), SCHED_FIFO, &prio);
      prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); // wake-ups to the microsecond, not 50 us late
      auto next = start;
      auto last = start;
      const auto p = std::chrono::duration_cast<steady::duration>(std::chrono::duration<double>(period));
      for (long k = 0; k < ticks; ++k) {
        std::this_thread::sleep_until(next - std::chrono::microseconds(200));
        while (steady::now() < next) {
        }
        const auto now = steady::now();
        if (now - next > p / 2) ++misses;
        if (k > 0) periods.push_back(std::chrono::duration<double, std::micro>(now - last).count());
        last = now;
        servo.tick(static_cast<double>(k) * period);
        device->advance(period);
        next += p;
        if (now - next > 10 * p) next = now + p; // far behind: resynchronise rather than burst
      }
      done = true;
    });
    // Physics on this thread, paced to wall time.
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
    elapsed = std::chrono::duration<double>(steady::now() - start).count();
  }
  HapticsReport rep = std::move(servo.report());
  rep.samples = static_cast<long>(rep.t.size());
  rep.rate_hz_mean =
      periods.empty()
          ? 0
          : 1e6 / (std::accumulate(periods.begin(), periods.end(), 0.0) / static_cast<double>(periods.size()));
  rep.period_p99_us = percentile(periods, 0.99);
  rep.period_max_us = periods.empty() ? 0 : *std::max_element(periods.begin(), periods.end());
  rep.deadline_misses = misses;
  rep.physics_steps = static_cast<long>(physics.step_times().size());
  rep.physics_step_median_us = percentile(physics.step_times(), 0.5);
  (void)elapsed;
  return rep;
}

void write_haptics(const HapticsReport& r, const std::filesystem::path& dir, const std::string& scene_name) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir.string() + ": cannot create output folder: " + ec.message());
  std::ostringstream csv;
  csv << std::setprecision(10) << "t,hx,hy,fx,fy\n";
  for (std::size_t k = 0; k < r.t.size(); ++k)
    csv << r.t[k] << ',' << r.hx[k] << ',' << r.hy[k] << ',' << r.fx[k] << ',' << r.fy[k] << '\n';
  nlohmann::ordered_json j;
  j["scene"] = scene_name;
  j["samples"] = r.samples;
  j["rate_hz_mean"] = r.rate_hz_mean;
  j["period_p99_us"] = r.period_p99_us;
  j["period_max_us"] = r.period_max_us;
  j["deadline_misses"] = r.deadline_misses;
  j["max_force"] = r.max_force;
  j["saturated_samples"] = r.saturated_samples;
  j["nonfinite_samples"] = r.nonfinite_samples;
  j["energy_to_user"] = r.energy_to_user;
  j["fault_time"] = r.fault_time;
  j["force_zero_time"] = r.force_zero_time;
  j["physics_steps"] = r.physics_steps;
  j["physics_step_median_us"] = r.physics_step_median_us;
  const std::pair<const char*, std::string> files[] = {{"haptics.csv", csv.str()}, {"summary.json", j.dump(2) + "\n"}};
  for (const auto& [name, text] : files) {
    std::ofstream f(dir / (std::string(name) + ".part"));
    f << text;
    if (!f) throw InputError((dir / name).string() + ": cannot write");
  }
  for (const auto& [name, text] : files) std::filesystem::rename(dir / (std::string(name) + ".part"), dir / name);
}

} // namespace vtb
