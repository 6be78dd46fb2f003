#pragma once
// Internal to reference_fem: the time loop that the serial and the distributed solvers share.

#include "time_scheme.hh"

#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace vtb::fem {

/// The static solve once at `duration` (or at every sample time after 0, scheme.static_path), or steps of the scheme's
/// dt up to it (ceil(D / dt) steps), with samples at sample_times(duration, output_interval): each is interpolated
/// within its step from the states at the step's ends (record(t) appends a sample of the
/// current state, interpolate(times) replaces the last two by the samples at those times),
/// stopping at the first step whose displacement is not finite (rep.stable = false, with the
/// time). step(t) advances to t, finite() says whether the displacement is finite. Fills rep's
/// step counts and step times.
template <class Step, class Finite, class Record, class Interpolate>
void march(const TimeScheme& scheme, double duration, double output_interval, RunReport& rep, Step&& step,
           Finite&& finite, Record&& record, Interpolate&& interpolate) {
  std::vector<double> seconds;
  const auto loop_start = std::chrono::steady_clock::now();
  const auto timed_step = [&](double t) {
    const auto a = std::chrono::steady_clock::now();
    step(t);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  };
  if (scheme.static_path) {
    record(0.0);
    const std::vector<double> times = sample_times(duration, output_interval);
    for (std::size_t k = 1; k < times.size(); ++k) {
      timed_step(times[k]);
      ++rep.steps_taken;
      if (!finite()) {
        rep.stable = false;
        rep.failure = "non-finite displacement";
        rep.failure_time = times[k];
        break;
      }
      record(times[k]);
    }
    rep.steps = static_cast<long>(times.size()) - 1;
  } else if (scheme.is_static) {
    timed_step(duration);
    rep.steps = rep.steps_taken = 1;
    record(duration);
  } else {
    const long steps = std::max(1L, static_cast<long>(std::ceil(duration / scheme.dt - 1e-9)));
    rep.steps = steps;
    seconds.reserve(static_cast<std::size_t>(steps));
    SampleSchedule samples(duration, output_interval);
    record(0.0);
    double t0 = 0.0;
    for (long k = 0; k < steps; ++k) {
      const double t = static_cast<double>(k + 1) * scheme.dt;
      const bool crossing = samples.due(t, scheme.dt);
      if (crossing) record(t0);
      timed_step(t);
      ++rep.steps_taken;
      t0 = t;
      if (!finite()) {
        rep.stable = false;
        rep.failure = "non-finite displacement";
        rep.failure_time = t;
        break;
      }
      if (crossing) {
        record(t);
        interpolate(samples.take(t, scheme.dt));
      }
    }
  }
  rep.step_seconds = step_stats(std::move(seconds));
  rep.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
}

} // namespace vtb::fem
