#pragma once
// Internal to reference_fem: the time loop that the serial and the distributed solvers share.

#include "time_scheme.hh"

#include "vtb/core/simulation.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace vtb::fem {

/// The static solve once at `duration`, or steps of the scheme's dt up to it, with a sample at
/// t = 0 and then every output_interval, stopping at the first step whose displacement is not
/// finite (rep.stable = false, with the time). step(t) advances to t, finite() says whether the
/// displacement is finite, record(t) takes a sample. Fills rep's step counts and step times.
template <class Step, class Finite, class Record>
void march(const TimeScheme& scheme, double duration, double output_interval, RunReport& rep, Step&& step,
           Finite&& finite, Record&& record) {
  std::vector<double> seconds;
  const auto timed_step = [&](double t) {
    const auto a = std::chrono::steady_clock::now();
    step(t);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  };
  if (scheme.is_static) {
    timed_step(duration);
    rep.steps = rep.steps_taken = 1;
    record(duration);
  } else {
    const long steps = std::max(1L, std::lround(duration / scheme.dt));
    rep.steps = steps;
    seconds.reserve(static_cast<std::size_t>(steps));
    long next_sample = 1;
    record(0.0);
    for (long k = 0; k < steps; ++k) {
      const double t = static_cast<double>(k + 1) * scheme.dt;
      timed_step(t);
      ++rep.steps_taken;
      if (!finite()) {
        rep.stable = false;
        rep.failure = "non-finite displacement";
        rep.failure_time = t;
        break;
      }
      if (t + 1e-6 * scheme.dt >= static_cast<double>(next_sample) * output_interval) {
        record(t);
        ++next_sample;
      }
    }
  }
  rep.step_seconds = step_stats(std::move(seconds));
}

} // namespace vtb::fem
