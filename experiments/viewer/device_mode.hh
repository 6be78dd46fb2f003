#pragma once
/// \file
/// The viewer's device mode (2D): the mouse is the scripted user's hand on a simulated ProCAT;
/// the handle's proxy collides with the deformed boundary (the haptics module's contact), the
/// virtual coupling's force is shaped (saturation, ramp-in, watchdog) and sent to the device,
/// and its reaction acts on the body. The servo runs at 1 kHz of simulated time, in lockstep
/// with the physics steps (each step runs the ticks that fall in it).

#include "live_sim.hh"

#include "vtb/haptics/contact2d.hh"
#include "vtb/haptics/device.hh"
#include "vtb/haptics/force_shaping.hh"

#include <array>
#include <optional>

namespace vtb::viewer {

class DeviceMode final : public StepHook<2> {
public:
  static constexpr int kTrace = 600;
  /// The scene's [haptics] settings when it has them, else the defaults of DESIGN.md §2.
  DeviceMode(const Mesh2& mesh, const Scene& scene);

  void before_step(const Model<2>& model, const State<2>& s, double dt, Nodal<2>& applied) override;

  Eigen::Vector2d hand = Eigen::Vector2d::Zero(); ///< where the user's hand holds the handle (scene coordinates)

  Eigen::Vector2d handle() const { return m_device ? m_device->true_position() : hand; }
  const Eigen::Vector2d& proxy() const { return m_proxy; }
  bool touching() const { return m_touching; }
  const Eigen::Vector2d& force() const { return m_force; } ///< last force sent to the device, N
  double max_force() const { return m_params.max_force; }
  long ticks() const { return m_ticks; }
  long saturated() const { return m_saturated; }
  bool faulted() const { return m_shaper.faulted(); }
  /// |F| of the last kTrace ticks (oldest first) into out; returns the count.
  int force_trace(float* out) const;

private:
  ForceShaper::Params m_params;
  double m_k, m_b, m_period;
  HandScript m_hand;
  std::optional<SimulatedProCAT> m_device; ///< made at the first tick, with the handle in the hand
  BoundaryContact m_contact;
  ForceShaper m_shaper;
  Nodal<2> m_x;
  Eigen::Vector2d m_proxy = Eigen::Vector2d::Zero(), m_force = Eigen::Vector2d::Zero();
  bool m_touching = false;
  long m_ticks = 0, m_saturated = 0;
  double m_t = 0;
  std::array<float, kTrace> m_trace{};
  int m_head = 0, m_count = 0;
};

} // namespace vtb::viewer
