// The servo thread's real-time set-up on Linux (realtime_thread.hh).
#include "realtime_thread.hh"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

namespace vtb {

/// The servo thread's real-time set-up (called on that thread): SCHED_FIFO priority, 1 ns
/// timer slack, and the pin to one core. Returns what was granted, for the summary.
std::vector<std::string> set_up_servo_thread(const HapticsOptions& opt) {
  std::vector<std::string> got;
  if (opt.realtime_priority) {
    // Granted to root (or CAP_SYS_NICE); else an ordinary thread, and the misses tell.
    sched_param prio{};
    prio.sched_priority = 80;
    got.push_back(pthread_setschedparam(pthread_self(), SCHED_FIFO, &prio) == 0 ? "fifo" : "fifo-denied");
  }
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); // wake-ups to the microsecond, not 50 us late
  if (opt.pin_cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(opt.pin_cpu, &set);
    got.push_back(pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0 ? "pinned" : "pinned-denied");
  }
  return got;
}

/// Moves the calling thread to every core it may use but `cpu` (nothing if that is the only one).
void keep_off_cpu(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (pthread_getaffinity_np(pthread_self(), sizeof set, &set) != 0) return;
  CPU_CLR(cpu, &set);
  if (CPU_COUNT(&set) > 0) pthread_setaffinity_np(pthread_self(), sizeof set, &set);
}

} // namespace vtb
