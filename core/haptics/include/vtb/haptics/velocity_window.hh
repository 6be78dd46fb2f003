#pragma once
/// \file
/// The handle's velocity from its encoder: first-order adaptive windowing (end-fit FOAW;
/// Janabi-Sharifi, Hayward and Chen, IEEE TCST 8(6), 2000), the estimator haptic devices use
/// on quantised positions.
///
/// Each new sample y_k takes the longest window n <= kMaxWindow for which the line through
/// y_{k-n} and y_k passes within one count of every sample between them; the velocity is that
/// line's slope. One count is the bound because each measured position is within half a count
/// of the true one: on a straight path the line through two measured ends is off by up to half
/// a count, and a sample between them by up to half a count more. So a steady motion is
/// followed without lag (the window stays the longest), an acceleration shortens the window
/// to what it allows, and a handle held still across a count boundary, whose measured position
/// flips by one count, reads at most one count over kMaxWindow samples (a first-order
/// difference reads one count per sample: the coupling's damper turned that into a force
/// change of several mN every cycle). Per axis; no allocation.

#include <Eigen/Core>

#include <array>

namespace vtb {

class AdaptiveWindowVelocity {
public:
  static constexpr int kMaxWindow = 16; ///< samples: 16 ms at 1 kHz
  /// `count`: the encoder's resolution (m); the first sample starts the history at rest.
  explicit AdaptiveWindowVelocity(double count) : m_count(count) {}
  /// Takes the measured position at time t (s, increasing) and returns the velocity estimate.
  const Eigen::Vector2d& add(double t, const Eigen::Vector2d& measured);
  const Eigen::Vector2d& velocity() const { return m_velocity; }

private:
  double slope(int axis) const;
  double m_count;
  std::array<double, kMaxWindow + 1> m_t{};
  std::array<Eigen::Vector2d, kMaxWindow + 1> m_y{};
  int m_head = -1, m_size = 0; ///< the newest sample's slot; samples held
  Eigen::Vector2d m_velocity = Eigen::Vector2d::Zero();
};

} // namespace vtb
