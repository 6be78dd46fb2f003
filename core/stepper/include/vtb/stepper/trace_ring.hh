#pragma once
/// \file
/// The last N samples of a scalar for a live plot (the viewer's probe and force traces): a
/// fixed ring, no allocation when pushed.

#include <algorithm>
#include <array>
#include <cstddef>

namespace vtb {

template <int N> class TraceRing {
public:
  static constexpr int capacity = N;

  void push(float v) {
    m_v[static_cast<std::size_t>(m_head)] = v;
    m_head = (m_head + 1) % N;
    m_count = std::min(m_count + 1, N);
  }
  void clear() { m_head = m_count = 0; }
  /// The samples held, oldest first, into `out` (room for N); returns their count.
  int copy_to(float* out) const {
    for (int k = 0; k < m_count; ++k) out[k] = m_v[static_cast<std::size_t>((m_head - m_count + k + N) % N)];
    return m_count;
  }

private:
  std::array<float, N> m_v{};
  int m_head = 0, m_count = 0;
};

} // namespace vtb
