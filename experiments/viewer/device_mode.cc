#include "device_mode.hh"

#include "vtb/base/input_error.hh"
#include "vtb/haptics/coupling.hh"
#include "vtb/haptics/devices/plugin_device.hh"
#include "vtb/haptics/local_model.hh"

#include <algorithm>
#include <cmath>
#include <utility>

namespace vtb::viewer {
namespace {

HandScript still_hand(const Scene& scene) {
  HandScript h;
  h.waypoints = {Eigen::Vector2d(0.0, 0.0)};
  if (scene.haptics && scene.haptics->hand) h.grip_stiffness = scene.haptics->hand->grip_stiffness;
  return h;
}

} // namespace

std::unique_ptr<HapticDevice> open_device_driver(const Scene& scene, const std::string& driver) {
  if (driver.empty() || driver == "procat-sim") return nullptr;
  if (driver.rfind("plugin:", 0) != 0 || driver.size() == 7)
    throw InputError("--device=" + driver +
                     ": the viewer takes procat-sim or plugin:PATH (the UDP bridge, the replay and the null device "
                     "run in `vtb haptics`)");
  DeviceSpec spec;
  if (scene.haptics) {
    spec.max_force = scene.haptics->max_force;
    spec.rate_hz = scene.haptics->rate;
  }
  return PluginDevice::load(driver.substr(7), scene.haptics ? scene.haptics->plugin_config : "", spec);
}

template <int dim>
DeviceMode<dim>::DeviceMode(const Mesh<dim>& mesh, const Scene& scene, std::unique_ptr<HapticDevice> driver)
    : m_driver(std::move(driver)),
      // A driver's limit is the smaller of the scene's and its own (plugin_device.hh).
      m_params{m_driver        ? m_driver->spec().max_force
               : scene.haptics ? scene.haptics->max_force
                               : 4.0,
               0.2, 0.03, 0.05},
      m_k(std::min(scene.haptics ? scene.haptics->coupling_stiffness : 400.0, DeviceSpec{}.max_stiffness)),
      m_b(scene.haptics ? scene.haptics->coupling_damping : 2.0),
      m_period(1.0 / (scene.haptics ? scene.haptics->rate : 1000.0)), m_plane(device_plane(scene, mesh)),
      m_hand(still_hand(scene)),
      m_contact(mesh, 1, (scene.haptics ? *scene.haptics : HapticsDesc{}).tip_radius_for(dim), scene.material),
      m_probe(m_k, m_b, 1), m_shaper(m_params), m_x(mesh.points),
      m_fallback(half_space_tip_compliance(dim, scene.material.young_modulus, scene.material.poisson_ratio,
                                           m_contact.tip().radius())) {}

template <int dim> int DeviceMode<dim>::ticks_in(double dt) const {
  return std::max(1, static_cast<int>(std::lround(dt / m_period)));
}

template <int dim> void DeviceMode<dim>::before_step(const Model<dim>& model, State<dim>& s, double dt) {
  // The step's force on the body from the ticks since the last step (as the session's physics
  // takes it): a step of one tick its force, a longer one the spring to the anchor its ticks
  // held (applied_force), on the last tick's footprint with the coupling's stiffness and
  // damping by the same weights in one group, for the solvers that take them implicitly.
  m_dt = dt;
  m_model.valid = false;
  const Footprint& fp = m_footprint;
  const bool slow = ticks_in(dt) > 1;
  if (fp.count == 0) { // the last tick did not touch: a contact that ended gives its force alone
    const ForceHistory<dim>& h = m_probe.history();
    if (slow && h.touched.count > 0) apply_force_to_body<dim>(h.touched, ended_contact_force<dim>(h), s);
    return;
  }
  const Vec<dim> at = footprint_mean<dim>(fp, model.net.rest) + footprint_mean<dim>(fp, s.u);
  const Vec<dim> f = slow && m_probe.history().cycles > 0
                         ? applied_force<dim>(m_probe.history(), at, tip_stiffness(m_k, fp))
                         : m_force_on_body;
  apply_to_body<dim>(fp, f, m_k, m_b, kDeviceGroup, s);
  m_model.applied = f;
  m_model.valid = slow && m_contact.tip().radius() > 0;
}

template <int dim>
void DeviceMode<dim>::after_step(const Model<dim>& model, const State<dim>& s, const Integrator<dim>& integrator) {
  // The contact's compliance over the step just taken (the solver's, else the half-space's).
  if (m_model.valid) {
    typename LocalModel<dim>::Mat c;
    if (integrator.coupling_compliance(kDeviceGroup, c) && c.allFinite()) {
      m_model.compliance = c;
    } else {
      m_model.compliance = m_fallback * LocalModel<dim>::Mat::Identity();
      m_model.valid = m_fallback > 0;
    }
  }
  // The ticks that fall in the step, against the body it reached: its nodes moved back with
  // their velocities to each tick's time (the tick at the step's end sees them as they are).
  const int n = ticks_in(m_dt);
  const double h = m_dt / n;
  if (!m_driver && !m_device) { // the handle starts where the hand is (not dragged in from the origin)
    m_hand.waypoints = {m_hand_device, m_hand_device};
    m_device.emplace(DeviceSpec{}, m_hand);
  }
  if (m_device) m_device->move_hand_to(m_hand_device, m_dt); // over the step's ticks: the hand moves, it does not jump
  HapticDevice& device = m_driver ? *m_driver : static_cast<HapticDevice&>(*m_device);
  m_x = model.net.rest + s.u;
  const bool finite = m_x.allFinite() && s.v.allFinite();
  if (finite) m_contact.refit(m_x);
  m_probe.set_blend_cycles(n);
  for (int k = 1; k <= n; ++k) {
    Eigen::Vector2d pos, vel;
    device.read(pos, vel);
    m_handle_device = pos;
    const Vec<dim> handle = m_plane.to_world(pos);
    const Vec<dim> raw =
        m_probe.cycle(m_contact, 0, handle, m_plane.axes * vel,
                      typename ProbeCoupling<dim>::Body{m_x, s.v, (k - n) * h, k == 1, finite, &m_model});
    const ContactResult<dim>& c = m_probe.contact();
    const Vec<dim> f = m_shaper.shape(raw, m_t, m_t, finite);
    m_probe.rendered(f);
    m_force_on_body = -f;
    m_force_device = m_plane.axes.transpose() * f;
    m_saturated += m_shaper.last_saturated();
    device.command(m_force_device);
    device.advance(h);
    m_t += h;
    ++m_ticks;
    m_proxy = c.touching ? c.proxy : handle;
    m_footprint = c.touching ? c.footprint : Footprint{};
    m_trace.push(static_cast<float>(m_force_device.norm()));
  }
}

template <int dim> int DeviceMode<dim>::force_trace(float* out) const {
  return m_trace.copy_to(out);
}

template class DeviceMode<2>;
template class DeviceMode<3>;

} // namespace vtb::viewer
