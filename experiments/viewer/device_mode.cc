#include "device_mode.hh"

#include "vtb/haptics/coupling.hh"

#include <algorithm>
#include <cmath>

namespace vtb::viewer {
namespace {

HandScript still_hand(const Scene& scene) {
  HandScript h;
  h.waypoints = {Eigen::Vector2d(0.0, 0.0)};
  if (scene.haptics && scene.haptics->hand) h.grip_stiffness = scene.haptics->hand->grip_stiffness;
  return h;
}

} // namespace

template <int dim>
DeviceMode<dim>::DeviceMode(const Mesh<dim>& mesh, const Scene& scene)
    : m_params{scene.haptics ? scene.haptics->max_force : 4.0, 0.2, 0.03, 0.05},
      m_k(std::min(scene.haptics ? scene.haptics->coupling_stiffness : 400.0, DeviceSpec{}.max_stiffness)),
      m_b(scene.haptics ? scene.haptics->coupling_damping : 2.0),
      m_period(1.0 / (scene.haptics ? scene.haptics->rate : 1000.0)), m_plane(device_plane(scene, mesh)),
      m_hand(still_hand(scene)),
      m_contact(mesh, 1, (scene.haptics ? *scene.haptics : HapticsDesc{}).tip_radius_for(dim), scene.material),
      m_shaper(m_params), m_x(mesh.points) {}

template <int dim> void DeviceMode<dim>::before_step(const Model<dim>& model, State<dim>& s, double dt) {
  // The ticks that fall in [t, t + dt): at least one per step.
  const int n = std::max(1, static_cast<int>(std::lround(dt / m_period)));
  const double h = dt / n;
  if (!m_device) { // the handle starts where the hand is (not dragged in from the origin)
    m_hand.waypoints = {m_hand_device};
    m_device.emplace(DeviceSpec{}, m_hand);
  }
  SimulatedProCAT& device = *m_device;
  device.hold_hand_at(m_hand_device);
  m_x = model.net.rest + s.u;
  const bool finite = m_x.allFinite() && s.v.allFinite();
  if (finite) m_contact.refit(m_x);
  Footprint footprint;
  // Several ticks a step: the local model of the last step (its compliance C and force g): the
  // contact on the body moved by C (f_prev - g), the coupling in series with C.
  const bool modelled = n > 1 && m_model.valid && m_contact.tip().radius() > 0;
  ForceHistory<dim> history;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector2d pos, vel;
    device.read(pos, vel);
    const Vec<dim> handle = m_plane.to_world(pos);
    LocalModel<dim> local = m_model;
    const Vec<dim> f_prev = m_touching ? m_last_solved : Vec<dim>::Zero();
    Vec<dim> shift = modelled ? Vec<dim>(local.compliance * (f_prev - local.applied)) : Vec<dim>::Zero();
    if (n > 1 && m_touching) // the body's free motion at the tip since the step began
      shift += (k * h) * footprint_mean<dim>(m_footprint, s.v);
    local.applied = f_prev;
    ContactResult<dim> c;
    if (finite) c = m_contact.update(0, Vec<dim>(handle - shift), m_x);
    if (c.touching) c.proxy += shift;
    Vec<dim> raw = Vec<dim>::Zero(), proxy = c.proxy;
    if (c.touching) {
      raw = virtual_coupling<dim>(c, handle, m_plane.axes * vel, s.v, m_k, m_b);
      if (modelled) {
        raw = solve_against_local_model<dim>(raw, c.proxy - handle, tip_stiffness(m_k, c.footprint), local);
        proxy += local.compliance * (-raw - local.applied);
      }
    }
    m_last_solved = -raw;
    const Vec<dim> f = m_shaper.shape(raw, m_t, m_t, finite);
    m_force_device = m_plane.axes.transpose() * f;
    m_saturated += m_shaper.last_saturated();
    device.command(m_force_device);
    device.advance(h);
    m_t += h;
    ++m_ticks;
    m_touching = c.touching;
    m_proxy = c.touching ? c.proxy : handle;
    m_footprint = c.footprint;
    m_normal = c.normal;
    if (c.touching) {
      footprint = c.footprint;
      history.sum -= f;
      history.proxy_sum += proxy;
      ++history.cycles;
    }
    m_trace[static_cast<std::size_t>(m_head)] = static_cast<float>(m_force_device.norm());
    m_head = (m_head + 1) % kTrace;
    m_count = std::min(m_count + 1, kTrace);
  }
  // The step's force on the body: the ticks' mean (a step of several ticks: the spring to the
  // anchor they held, applied_force), on the last footprint's nodes, with the coupling's
  // stiffness and damping by the same weights in one group for the solvers that take them
  // implicitly (as vtb haptics does: docs/haptics.md).
  m_model.valid = false;
  if (footprint.count > 0) {
    Vec<dim> f = history.sum / n; // the ticks' forces on the body, summed over those in contact
    if (n > 1) f = applied_force<dim>(history, footprint_mean<dim>(footprint, m_x), tip_stiffness(m_k, footprint));
    apply_to_body<dim>(footprint, f, m_k, m_b, kDeviceGroup, s);
    m_model.applied = f;
    m_model.valid = n > 1;
  }
}

template <int dim> void DeviceMode<dim>::after_step(const Integrator<dim>& integrator) {
  // The contact's compliance over the step just taken, for the next step's ticks.
  if (m_model.valid) m_model.valid = integrator.coupling_compliance(kDeviceGroup, m_model.compliance);
}

template <int dim> int DeviceMode<dim>::force_trace(float* out) const {
  for (int k = 0; k < m_count; ++k)
    out[k] = m_trace[static_cast<std::size_t>((m_head - m_count + k + kTrace) % kTrace)];
  return m_count;
}

template class DeviceMode<2>;
template class DeviceMode<3>;

} // namespace vtb::viewer
