#include "vtb/haptics/velocity_window.hh"

#include <cmath>

namespace vtb {

const Eigen::Vector2d& AdaptiveWindowVelocity::add(double t, const Eigen::Vector2d& measured) {
  m_head = (m_head + 1) % (kMaxWindow + 1);
  m_t[m_head] = t;
  m_y[m_head] = measured;
  if (m_size < kMaxWindow + 1) ++m_size;
  for (int a = 0; a < 2; ++a) m_velocity[a] = slope(a);
  return m_velocity;
}

double AdaptiveWindowVelocity::slope(int axis) const {
  constexpr int slots = kMaxWindow + 1;
  const auto at = [&](int back) { return (m_head - back + slots) % slots; }; // back samples ago
  const double tk = m_t[m_head], yk = m_y[m_head][axis];
  double best = 0.0;
  for (int n = 1; n < m_size; ++n) {
    const double dt = tk - m_t[at(n)];
    if (!(dt > 0)) break;
    const double b = (yk - m_y[at(n)][axis]) / dt;
    bool fits = true;
    for (int i = 1; i < n && fits; ++i)
      fits = std::abs(m_y[at(i)][axis] - (yk - b * (tk - m_t[at(i)]))) <=
             m_count * (1 + 1e-9); // one count, with the rounding of t and y
    if (!fits) break;
    best = b;
  }
  return best;
}

} // namespace vtb
