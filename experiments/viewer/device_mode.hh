#pragma once
/// \file
/// The viewer's device mode: the mouse is the scripted user's hand on a simulated ProCAT, or a
/// driver loaded at run time (`--device=plugin:PATH`, device_abi.h) is the device and its handle
/// moves the tool (the mouse then moves nothing). In 2D
/// the device's plane is the body's; in 3D the scene's [haptics.plane] places it (as in
/// `vtb haptics`): the mouse moves the hand in that plane, the handle's proxy collides with the
/// deformed surface (the haptics module's contact, one AABB tree), the virtual coupling's force
/// is shaped whole (saturation, ramp-in, watchdog), the device renders its in-plane part and the
/// body receives the whole reaction. The servo runs at 1 kHz of simulated time, in lockstep with
/// the physics steps as `vtb haptics --lockstep` runs them: each step is taken first, then the
/// servo ticks that fall in it run against the body it reached, and the next step takes their
/// force. Each tick is the session's own (ProbeCoupling): a step of several servo periods (a
/// large body at the rate it affords) has its ticks solve the coupling against the local
/// contact model of that step (local_model.hh), its change blended in over the step, and the
/// next step takes the spring to the anchor they held.

#include "vtb/stepper/live_sim.hh"
#include "vtb/stepper/trace_ring.hh"

#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/device.hh"
#include "vtb/haptics/device_plane.hh"
#include "vtb/haptics/force_shaping.hh"
#include "vtb/haptics/local_model.hh"
#include "vtb/haptics/probe_coupling.hh"

#include <memory>
#include <optional>
#include <string>

namespace vtb::viewer {

/// The device `--device=` names, opened: null for "" or "procat-sim" (the simulated ProCAT),
/// else "plugin:PATH" opened with the scene's [haptics] limit, rate and plugin_config.
/// InputError, one line naming it: another kind of device, or a driver that cannot be opened.
std::unique_ptr<HapticDevice> open_device_driver(const Scene& scene, const std::string& driver);

template <int dim> class DeviceMode final : public StepHook<dim> {
public:
  static constexpr int kTrace = 600;
  /// The coupling group the device's footprint takes in State::applied_group (the drags' are
  /// their pull index, below it).
  static constexpr int kDeviceGroup = 1000;
  /// The scene's [haptics] settings when it has them, else the defaults of docs/scenes.md.
  /// `driver`: null (the simulated ProCAT, held by the mouse), or open_device_driver's.
  DeviceMode(const Mesh<dim>& mesh, const Scene& scene, std::unique_ptr<HapticDevice> driver = nullptr);

  void before_step(const Model<dim>& model, State<dim>& s, double dt) override;
  void after_step(const Model<dim>& model, const State<dim>& s, const Integrator<dim>& integrator) override;

  /// Where the user's hand holds the handle: a body point, taken to the device's plane (a
  /// driver's handle is moved by its user, not by this).
  void set_hand(const Vec<dim>& p) { m_hand_device = m_plane.to_device(p); }
  /// The device's name: "procat-sim", or what the driver calls itself.
  std::string device_name() const { return m_driver ? m_driver->name() : "procat-sim"; }
  const DevicePlane<dim>& plane() const { return m_plane; }

  Vec<dim> hand() const { return m_driver ? handle() : m_plane.to_world(m_hand_device); }
  Vec<dim> handle() const {
    return m_plane.to_world(m_driver ? m_handle_device : m_device ? m_device->true_position() : m_hand_device);
  }
  const Vec<dim>& proxy() const { return m_proxy; }
  bool touching() const { return m_probe.contact().touching; }
  /// The tool tip's footprint at the last tick (nodes and weights; empty when not touching).
  const Footprint& footprint() const { return m_footprint; }
  /// The tip's face's outward normal at the last tick (when touching).
  const Vec<dim>& tip_normal() const { return m_probe.contact().normal; }
  /// The body's nodes as the last tick saw them (the footprint's nodes index them).
  const Nodal<dim>& positions() const { return m_x; }
  double tip_radius() const { return m_contact.tip().radius(); }
  /// The last force the device rendered (its in-plane part), in the body's space, N.
  Vec<dim> force() const { return m_plane.axes * m_force_device; }
  double max_force() const { return m_params.max_force; }
  long ticks() const { return m_ticks; }
  long saturated() const { return m_saturated; }
  bool faulted() const { return m_shaper.faulted(); }
  /// |F| of the last kTrace ticks (oldest first) into out; returns the count.
  int force_trace(float* out) const;

private:
  /// Servo ticks in a step of dt: at least one.
  int ticks_in(double dt) const;

  std::unique_ptr<HapticDevice> m_driver; ///< a driver loaded at run time, or null (the simulated ProCAT)
  typename BasicForceShaper<dim>::Params m_params;
  double m_k, m_b, m_period;
  DevicePlane<dim> m_plane;
  HandScript m_hand;
  Eigen::Vector2d m_hand_device = Eigen::Vector2d::Zero();
  std::optional<SimulatedProCAT> m_device; ///< made at the first tick, with the handle in the hand (no driver)
  Eigen::Vector2d m_handle_device = Eigen::Vector2d::Zero(); ///< the driver's handle at the last tick
  Contacts<dim> m_contact;                                   ///< one probe
  ProbeCoupling<dim> m_probe;
  BasicForceShaper<dim> m_shaper;
  Nodal<dim> m_x;
  Vec<dim> m_proxy = Vec<dim>::Zero();
  Footprint m_footprint; ///< the last tick's (empty when not touching)
  Eigen::Vector2d m_force_device = Eigen::Vector2d::Zero();
  long m_ticks = 0, m_saturated = 0;
  LocalModel<dim> m_model; ///< the last step's contact model (valid: it coupled the tip and has a compliance)
  Vec<dim> m_force_on_body = Vec<dim>::Zero(); ///< the last tick's
  double m_fallback;                           ///< m/N: the half-space's compliance under the tip (0: none)
  double m_dt = 0;                             ///< the step being taken
  double m_t = 0;
  TraceRing<kTrace> m_trace; ///< |F| the device rendered, per tick
};

} // namespace vtb::viewer
