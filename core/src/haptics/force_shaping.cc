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
  const bool stalled = t - physics_time > m_p.stall_after;
  if (!m_faulted && (stalled || !physics_finite || !raw.allFinite())) {
    m_faulted = true;
    m_fault_time = t;
  }
  if (m_faulted) {
    const double scale = std::clamp(1.0 - (t - m_fault_time) / m_p.ramp_out, 0.0, 1.0);
    return saturate(m_last_good * scale, m_p.max_force, &m_saturated);
  }
  const double scale = m_p.ramp_in > 0 ? std::clamp(t / m_p.ramp_in, 0.0, 1.0) : 1.0;
  m_last_good = saturate(raw * scale, m_p.max_force, &m_saturated);
  return m_last_good;
}

} // namespace vtb
