#include "vtb/haptics/force_shaping.hh"

#include <algorithm>
#include <cmath>

namespace vtb {

template <int n>
Eigen::Matrix<double, n, 1> saturate(const Eigen::Matrix<double, n, 1>& f, double max_force, bool* saturated) {
  if (saturated) *saturated = false;
  if (!f.allFinite()) return Eigen::Matrix<double, n, 1>::Zero();
  const double norm = f.norm();
  if (norm <= max_force) return f;
  if (saturated) *saturated = true;
  return f * (max_force / norm);
}

template <int n>
typename BasicForceShaper<n>::Vec BasicForceShaper<n>::shape(const Vec& raw, double t, double physics_time,
                                                             bool physics_finite) {
  const bool stalled = t - physics_time > m_p.stall_after;
  if (!m_faulted && (stalled || !physics_finite || !raw.allFinite())) {
    m_faulted = true;
    m_fault_time = t;
    m_reason = stalled ? "stall" : !physics_finite ? "physics" : "force";
  }
  if (m_faulted) {
    const double scale = std::clamp(1.0 - (t - m_fault_time) / m_p.ramp_out, 0.0, 1.0);
    return saturate<n>(m_last_good * scale, m_p.max_force, &m_saturated);
  }
  const double scale = m_p.ramp_in > 0 ? std::clamp(t / m_p.ramp_in, 0.0, 1.0) : 1.0;
  m_last_good = saturate<n>(raw * scale, m_p.max_force, &m_saturated);
  return m_last_good;
}

template Eigen::Matrix<double, 2, 1> saturate<2>(const Eigen::Matrix<double, 2, 1>&, double, bool*);
template Eigen::Matrix<double, 3, 1> saturate<3>(const Eigen::Matrix<double, 3, 1>&, double, bool*);
template class BasicForceShaper<2>;
template class BasicForceShaper<3>;

} // namespace vtb
