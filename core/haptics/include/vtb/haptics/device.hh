#pragma once
/// \file
/// Haptic devices: the interface the servo loop talks to, the simulated 2-DOF ProCAT pushed by
/// a scripted hand, and a device that replays a recorded handle trajectory.

#include "vtb/haptics/velocity_window.hh"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace vtb {

struct DeviceSpec {
  Eigen::Vector2d workspace_min{-0.1, -0.1}, workspace_max{0.3, 0.2}; ///< m
  double max_force = 4.0;                                             ///< N
  double max_stiffness = 2000.0;                                      ///< N/m the device renders stably
  double rate_hz = 1000.0;                                            ///< nominal servo rate
};

/// A device's link to vtb, for the run line and summary.json: what a device in another process
/// (udp_device.hh) sent and lost, or what a plug-in's read reported. Zero for an in-process one.
struct DeviceLinkStats {
  long received = 0;                     ///< packets taken (each the newest so far)
  long stale = 0;                        ///< packets older than one already taken (out of order), dropped
  long lost = 0;                         ///< sequence numbers never seen
  long malformed = 0;                    ///< packets of the wrong size, magic, version or kind, dropped
  long faults = 0;                       ///< reads or writes the device failed (0 N is rendered from the first)
  long silent_cycles = 0;                ///< servo cycles commanded 0 N because the link was silent past its watchdog
  double first_silent_time = -1;         ///< s of servo time when the link first fell silent (-1: never)
  double rtt_p50_us = 0, rtt_p99_us = 0; ///< the link's round trip, without the time a packet waited to be read
};

/// What the servo loop needs from a device. Implementations own their state; none is shared.
/// read and command are called from the servo thread alone, once per cycle, and allocate nothing.
class HapticDevice {
public:
  virtual ~HapticDevice() = default;
  virtual const DeviceSpec& spec() const = 0;
  /// Handle position and velocity (m, m/s) as the device measures them.
  virtual void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const = 0;
  /// The force to render on the handle (N); devices clamp it to their own limit as well.
  virtual void command(const Eigen::Vector2d& force) = 0;
  /// The force with the local model about it, F(x) = force - stiffness (x - anchor), for a
  /// device that renders between servo cycles; by default the force alone.
  virtual void command(const Eigen::Vector2d& force, double /*stiffness*/, const Eigen::Vector2d& /*anchor*/,
                       double /*t*/) {
    command(force);
  }
  /// Advances a simulated device's own physics by dt (a real device does nothing).
  virtual void advance(double dt) = 0;
  /// What the run line and summary.json call it.
  virtual std::string name() const { return "device"; }
  virtual DeviceLinkStats link_stats() const { return {}; }
  /// The last command went out as 0 N whatever was commanded (a silent link, a faulted
  /// plug-in): the session's record logs what the device got.
  virtual bool zeroed() const { return false; }
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
  std::string name() const override { return "procat-sim"; }
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
  void advance(double dt) override;
  std::string name() const override { return "replay"; }

private:
  /// The recorded path at time t, linear between samples (held past either end).
  Eigen::Vector2d position_at(double t) const;
  DeviceSpec m_spec;
  std::vector<double> m_time;
  std::vector<Eigen::Vector2d> m_pos;
  double m_t = 0;
  /// The velocity as the simulated ProCAT estimates it (its encoder's count), from the
  /// positions the replay reports at each advance: a recording of the device played back
  /// reads the velocities it read, so its coupling's damping gives the recorded forces.
  AdaptiveWindowVelocity m_velocity{SimulatedProCAT::Physical{}.encoder};
};

} // namespace vtb
