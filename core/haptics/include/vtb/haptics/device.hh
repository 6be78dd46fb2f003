#pragma once
/// \file
/// Haptic devices: the interface the servo loop talks to, the simulated 2-DOF ProCAT pushed by
/// a scripted hand, and a device that replays a recorded handle trajectory.

#include "vtb/haptics/velocity_window.hh"

#include <Eigen/Core>

#include <filesystem>
#include <vector>

namespace vtb {

struct DeviceSpec {
  Eigen::Vector2d workspace_min{-0.1, -0.1}, workspace_max{0.3, 0.2}; ///< m
  double max_force = 4.0;                                             ///< N
  double max_stiffness = 2000.0;                                      ///< N/m the device renders stably
  double rate_hz = 1000.0;                                            ///< nominal servo rate
};

/// What the servo loop needs from a device. Implementations own their state; none is shared.
class HapticDevice {
public:
  virtual ~HapticDevice() = default;
  virtual const DeviceSpec& spec() const = 0;
  /// Handle position and velocity (m, m/s) as the device measures them.
  virtual void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const = 0;
  /// The force to render on the handle (N); devices clamp it to their own limit as well.
  virtual void command(const Eigen::Vector2d& force) = 0;
  /// Advances a simulated device's own physics by dt (a real device does nothing).
  virtual void advance(double dt) = 0;
};

/// The scripted user: a hand that moves along waypoints (piecewise linear over `duration`)
/// and holds the handle through a grip spring.
struct HandScript {
  std::vector<Eigen::Vector2d> waypoints;
  double duration = 1.0;
  double grip_stiffness = 2000.0; ///< N/m
  Eigen::Vector2d at(double t) const;
};

/// The ProCAT as a 2-DOF planar handle: mass, viscous and Coulomb friction, encoder
/// quantisation (velocity by adaptive windowing), a force limit; the hand pulls it through the grip spring.
/// Deterministic.
class SimulatedProCAT final : public HapticDevice {
public:
  struct Physical {
    double mass = 0.15;    ///< kg, handle and linkage reflected at the handle
    double viscous = 0.5;  ///< N s/m
    double coulomb = 0.02; ///< N
    double encoder = 2e-6; ///< m per count
  };
  SimulatedProCAT(const DeviceSpec& spec, HandScript hand, Physical physical);
  SimulatedProCAT(const DeviceSpec& spec, HandScript hand) : SimulatedProCAT(spec, std::move(hand), Physical{}) {}
  const DeviceSpec& spec() const override { return m_spec; }
  void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const override;
  void command(const Eigen::Vector2d& force) override;
  void advance(double dt) override;
  double time() const { return m_t; }
  const Eigen::Vector2d& true_position() const { return m_x; }
  /// A live user (the viewer's mouse) instead of the script: the hand goes from where it is now
  /// to p in a straight line over the next `over` seconds, then holds there. A hand that jumped
  /// to each new target would kick the handle's grip mode (18 Hz, 1.5 % damped) at the rate of
  /// the targets: at a physics step of 55 ms it rang 2 cm deep. Allocation-free once the script
  /// has two waypoints.
  void move_hand_to(const Eigen::Vector2d& p, double over);

private:
  DeviceSpec m_spec;
  HandScript m_hand;
  Physical m_phys;
  double m_t = 0;
  double m_hand_start = 0; ///< the script's time 0 on the device's clock
  Eigen::Vector2d m_x, m_v = Eigen::Vector2d::Zero(), m_force = Eigen::Vector2d::Zero();
  Eigen::Vector2d m_measured;
  AdaptiveWindowVelocity m_velocity;
};

/// Replays a recorded handle trajectory (CSV with columns t,hx,hy, as haptics.csv has; probe
/// k > 0 reads hx_k,hy_k): the handle goes where the recording says, whatever force is commanded.
class ReplayDevice final : public HapticDevice {
public:
  ReplayDevice(const DeviceSpec& spec, const std::filesystem::path& csv, int probe = 0);
  const DeviceSpec& spec() const override { return m_spec; }
  void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const override;
  void command(const Eigen::Vector2d&) override {}
  void advance(double dt) override { m_t += dt; }

private:
  DeviceSpec m_spec;
  std::vector<double> m_time;
  std::vector<Eigen::Vector2d> m_pos;
  double m_t = 0;
};

} // namespace vtb
