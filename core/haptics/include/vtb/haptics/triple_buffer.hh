#pragma once
/// \file
/// A lock-free single-producer single-consumer triple buffer: the writer always has a buffer
/// to fill, the reader always sees the latest complete one, nobody waits or allocates.

#include <atomic>

namespace vtb {

template <typename T> class TripleBuffer {
public:
  explicit TripleBuffer(const T& initial) : m_buf{initial, initial, initial} {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// Writer: fill back(), then publish().
  T& back() { return m_buf[m_back]; }
  void publish() { m_back = m_middle.exchange(m_back | kFresh, std::memory_order_acq_rel) & kIndex; }

  /// Reader: fetch() takes the latest published buffer if there is a new one; front() reads it.
  bool fetch() {
    if (!(m_middle.load(std::memory_order_acquire) & kFresh)) return false;
    m_front = m_middle.exchange(m_front, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  const T& front() const { return m_buf[m_front]; }

private:
  static constexpr int kIndex = 3, kFresh = 4;
  T m_buf[3];
  int m_back = 0, m_front = 1;
  std::atomic<int> m_middle{2};
};

} // namespace vtb
