#pragma once
/// \file
/// What stands between the physics and the motors: saturation that keeps the direction, a
/// ramp-in at start, and a watchdog that ramps the force to zero when the physics stalls,
/// diverges or returns non-finite values. Pure and allocation-free: the servo loop calls it.
/// `n` is the dimension of the force being shaped: 2 for a plate, 3 for the coupling force of
/// a planar handle moving through a 3D body (the device renders its in-plane part).

#include <Eigen/Core>

namespace vtb {

/// |F| <= max_force with F's direction kept; a non-finite F becomes zero.
template <int n>
Eigen::Matrix<double, n, 1> saturate(const Eigen::Matrix<double, n, 1>& force, double max_force,
                                     bool* saturated = nullptr);
inline Eigen::Vector2d saturate(const Eigen::Vector2d& force, double max_force, bool* saturated = nullptr) {
  return saturate<2>(force, max_force, saturated);
}

template <int n> class BasicForceShaper {
public:
  using Vec = Eigen::Matrix<double, n, 1>;
  struct Params {
    double max_force = 4.0;    ///< N
    double ramp_in = 0.5;      ///< s from zero to full scale at start
    double ramp_out = 0.03;    ///< s from full scale to zero on a fault (well inside 50 ms)
    double stall_after = 0.01; ///< s without a physics update that counts as a stall (zero by 40 ms)
  };
  explicit BasicForceShaper(Params p) : m_p(p) {}

  /// The force to command at servo time t for the raw coupling force, given when the physics
  /// last published (`physics_time`) and whether what it published was finite. On a fault the
  /// last force commanded before it (the physics' output can no longer be trusted) ramps
  /// linearly to zero over ramp_out, and stays zero until the run ends: no jolt, no NaN.
  Vec shape(const Vec& raw, double t, double physics_time, bool physics_finite);

  bool faulted() const { return m_faulted; }
  /// What tripped the watchdog: "stall", "physics" (non-finite or runaway state), "force"
  /// (a non-finite coupling force); empty while it has not.
  const char* fault_reason() const { return m_reason; }
  double fault_time() const { return m_fault_time; }
  bool last_saturated() const { return m_saturated; }

private:
  Params m_p;
  bool m_faulted = false, m_saturated = false;
  double m_fault_time = -1;
  const char* m_reason = "";
  Vec m_last_good = Vec::Zero(); ///< the last force commanded before a fault
};

using ForceShaper = BasicForceShaper<2>;

} // namespace vtb
