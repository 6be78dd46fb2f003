#pragma once
// Internal to vtb::haptics: the servo thread's real-time set-up on Linux (SCHED_FIFO, timer
// slack, core pinning), apart from the session that runs the loop on it (session.cc).

#include "vtb/haptics/session.hh"

#include <string>
#include <vector>

namespace vtb {

/// Called on the servo thread: SCHED_FIFO priority, 1 ns timer slack, and the pin to one core.
/// Returns what was granted ("fifo", "pinned", or "x-denied"), for the summary.
std::vector<std::string> set_up_servo_thread(const HapticsOptions& opt);

/// Moves the calling thread to every core it may use but `cpu` (nothing if that is the only one).
void keep_off_cpu(int cpu);

} // namespace vtb
