#include "vtb/core/haptics/force_shaping.hh"

#include <algorithm>
#include <cmath>

namespace vtb {

Eigen::Vector2d saturate(const Eigen::Vector2d& f, double max_force, bool* saturated) {
  if (saturated) *saturated = false;
  if (!f.allFinite()) return Eigen::Vector2d::Zero();
  const double n = f.norm();
  if (n <= max_force) return f;
  if (saturated) *saturated = true;
  return f * (max_force / n);
}

Eigen::Vector2d ForceShaper::shape(const Eigen::Vector2d& raw, double t, double physics_time, bool physics_finite) {
  double scale = m_p.ramp_in > 0 ? std::clamp(t / m_p.ramp_in, 0.0, 1.0) : 1.0;
  const bool stalled = t - physics_time > m_p.stall_after;
  if (!m_faulted && (stalled || !physics_finite || !raw.allFinite())) {
    m_faulted = true;
    m_fault_time = t;
    m_scale_at_fault = scale;
  }
  if (m_faulted) {
    // Ramp down from the scale at the fault; the raw force may be garbage: hold the last
    // finite direction by using raw only when finite, else zero.
    scale = m_scale_at_fault * std::clamp(1.0 - (t - m_fault_time) / m_p.ramp_out, 0.0, 1.0);
  }
  const Eigen::Vector2d f = raw.allFinite() ? Eigen::Vector2d(raw * scale) : Eigen::Vector2d::Zero();
  return saturate(f, m_p.max_force, &m_saturated);
}

} // namespace vtb
