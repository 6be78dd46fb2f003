#pragma once
/// \file
/// The strain colour scale: viridis (perceptually uniform, readable in grey), sampled at
/// five stops and interpolated linearly.

#include <algorithm>
#include <array>
#include <cmath>

namespace vtb::viewer {

/// RGB in [0, 1] for s in [0, 1] (clamped; a non-finite s is magenta, a diverged cell).
inline std::array<float, 3> viridis(double s) {
  if (!std::isfinite(s)) return {1.0f, 0.0f, 1.0f};
  static constexpr std::array<std::array<float, 3>, 5> stops = {{{0.267f, 0.005f, 0.329f},
                                                                 {0.229f, 0.322f, 0.546f},
                                                                 {0.128f, 0.567f, 0.551f},
                                                                 {0.369f, 0.789f, 0.383f},
                                                                 {0.993f, 0.906f, 0.144f}}};
  const double x = std::clamp(s, 0.0, 1.0) * 4.0;
  const int k = std::min(3, static_cast<int>(x));
  const float f = static_cast<float>(x - k);
  std::array<float, 3> c{};
  for (int i = 0; i < 3; ++i)
    c[static_cast<std::size_t>(i)] = (1 - f) * stops[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] +
                                     f * stops[static_cast<std::size_t>(k) + 1][static_cast<std::size_t>(i)];
  return c;
}

} // namespace vtb::viewer
