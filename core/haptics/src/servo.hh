#pragma once
/// \file
/// The servo side of a haptics session: devices, proxies, the virtual coupling solved against
/// each probe's local contact model, force shaping and the record. No allocation in tick().

#include "exchange.hh"
#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/coupling.hh"
#include "vtb/haptics/device.hh"
#include "vtb/haptics/device_plane.hh"
#include "vtb/haptics/force_shaping.hh"
#include "vtb/haptics/probe_coupling.hh"
#include "vtb/haptics/session.hh"
#include "vtb/haptics/triple_buffer.hh"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace vtb {

/// The watchdog's stall limit for a physics stepping every dt: a publish overdue by
/// kStallPeriods of its periods, and never less than the 10 ms of a 1 kHz physics.
inline constexpr double kStallPeriods = 10.0;
inline double stall_limit(double physics_dt) {
  return std::max(0.01, kStallPeriods * physics_dt);
}

template <int dim> class Servo {
public:
  using Vec = Eigen::Matrix<double, dim, 1>;

  /// `physics_dt`: the physics' step, which sets the watchdog's stall limit (stall_limit).
  Servo(std::vector<std::unique_ptr<HapticDevice>>& devices, const Mesh<dim>& mesh, const MaterialDesc& material,
        const HapticsDesc& h, const DevicePlane<dim>& plane, long max_samples, double physics_dt,
        TripleBuffer<Snapshot<dim>>& snap, TripleBuffer<Commands<dim>>& cmd)
      : m_devices(devices), m_contacts(mesh, devices.size(), h.tip_radius_for(dim), material), m_h(h), m_plane(plane),
        m_snap(snap), m_cmd(cmd), m_x(mesh.points), m_max(max_samples), m_physics_dt(physics_dt),
        m_blend_cycles(static_cast<int>(std::lround(physics_dt * h.rate))) {
    m_probes.reserve(devices.size());
    m_rep.t.reserve(static_cast<std::size_t>(max_samples));
    m_rep.probes.resize(devices.size());
    for (std::size_t i = 0; i < devices.size(); ++i) {
      m_probes.emplace_back(h.coupling_stiffness, h.coupling_damping, m_blend_cycles);
      m_shapers.emplace_back(typename BasicForceShaper<dim>::Params{std::min(h.max_force, devices[i]->spec().max_force),
                                                                    0.5, 0.03, stall_limit(physics_dt)});
      for (auto* v : {&m_rep.probes[i].hx, &m_rep.probes[i].hy, &m_rep.probes[i].fx, &m_rep.probes[i].fy})
        v->reserve(static_cast<std::size_t>(max_samples));
    }
  }

  /// One servo cycle at servo time t, for every probe.
  void tick(double t) {
    const bool fresh = m_snap.fetch();
    const Snapshot<dim>& s = m_snap.front();
    if (fresh) m_arrival = t; // a new physics step: its force comes from the cycles from here on
    // The body's free motion between physics updates: the contact is found on the published
    // body, and its proxy moved with the footprint's velocity back to the cycle's time (the
    // tip's nodes', not the whole body's: the cycle's cost does not grow with the body). A
    // physics stepping every dt publishes up to dt less one servo period ahead of the servo; a
    // late snapshot is held, not extrapolated forward (extrapolated, a soft block's contact
    // chattered in real time). A physics stepping every period is never ahead.
    const double lead = std::max(0.0, m_physics_dt - 1.0 / m_h.rate);
    const double age = std::clamp(t - s.t, -lead, 0.0);
    const double age_whole = std::clamp(t - s.t, 0.0, 0.05);
    // A physics stepping every servo period (a body small enough) is extrapolated whole, as it
    // always was: its snapshot is at most one period old.
    const bool whole = m_blend_cycles <= 1;
    if (whole) m_x = s.x + age_whole * s.v;
    const Nodal<dim>& x = whole ? m_x : s.x;
    const bool finite = s.finite && (!whole || m_x.allFinite());
    if (fresh && finite) m_contacts.refit(s.x);
    const bool record = static_cast<long>(m_rep.t.size()) < m_max;
    if (record) m_rep.t.push_back(t);
    bool all_zero = true;
    Commands<dim>& out = m_cmd.back();
    for (std::size_t i = 0; i < m_devices.size(); ++i) {
      Eigen::Vector2d pos, vel;
      m_devices[i]->read(pos, vel);
      const Vec handle = m_plane.origin + m_plane.axes * pos;
      const LocalModel<dim>* model = i < s.models.size() ? &s.models[i] : nullptr;
      ProbeCoupling<dim>& probe = m_probes[i];
      const Vec raw = probe.cycle(m_contacts, i, handle, m_plane.axes * vel,
                                  typename ProbeCoupling<dim>::Body{x, s.v, age, fresh, finite, model});
      const ContactResult<dim>& c = probe.contact();
      if (probe.publish_change() >= 0) count_prediction(probe.publish_change());
      // The coupling force is shaped whole; a planar device renders its in-plane part (the
      // rest is taken by its mechanism), the body receives the whole reaction.
      const Vec f = m_shapers[i].shape(raw, t, m_arrival, finite);
      const Eigen::Vector2d fd = m_plane.axes.transpose() * f;
      // With the local model about the handle, for a device that renders between cycles.
      m_devices[i]->command(fd, c.touching ? m_h.coupling_stiffness : 0.0, pos, t);
      probe.rendered(f);
      out[i].footprint = c.touching ? c.footprint : Footprint{};
      out[i].force_on_body = -f;
      out[i].history = probe.history();
      if (c.touching) count_footprint(m_rep.probes[i], c.footprint);
      all_zero = all_zero && f.norm() == 0.0;
      // The record is what the device got: 0 N where the host zeroed it (a silent link).
      if (record) log(m_rep.probes[i], m_shapers[i], pos, vel, m_devices[i]->zeroed() ? Eigen::Vector2d::Zero() : fd);
      if (m_shapers[i].faulted() && m_rep.fault_time < 0) {
        m_rep.fault_time = m_shapers[i].fault_time();
        m_rep.fault_reason = m_shapers[i].fault_reason();
      }
    }
    m_cmd.publish();
    if (m_rep.fault_time >= 0 && m_rep.force_zero_time < 0 && all_zero) m_rep.force_zero_time = t;
  }

  HapticsReport& report() { return m_rep; }
  const TipFootprint<dim>& tip() const { return m_contacts.tip(); }
  /// The contact finders; the physics' thread prepares their next tree (Contacts::prepare).
  Contacts<dim>& contacts() { return m_contacts; }
  /// The local model's error: the coupling force's change at each publish in contact (N).
  double prediction_error_rms() const { return m_predictions ? std::sqrt(m_prediction_sq / m_predictions) : 0.0; }
  double prediction_error_max() const { return m_prediction_max; }

private:
  void count_prediction(double e) {
    ++m_predictions;
    m_prediction_sq += e * e;
    m_prediction_max = std::max(m_prediction_max, e);
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
  Nodal<dim> m_x; ///< a physics stepping every period: the body extrapolated whole
  HapticsReport m_rep;
  long m_max = 0;
  double m_physics_dt;
  double m_arrival = 0;                     ///< servo time at which the snapshot in use arrived
  int m_blend_cycles;                       ///< servo cycles in a physics step: a publish's change is blended over them
  std::vector<ProbeCoupling<dim>> m_probes; ///< per probe: its coupling against the local model
  long m_predictions = 0;
  double m_prediction_sq = 0, m_prediction_max = 0;
};

} // namespace vtb
