// Servo-loop timing of `vtb haptics` in real time, with the other core kept busy by a spinning
// thread (the worst case the issue names). Counters: mean rate, p99 and max period, deadline
// misses (cycles started more than half a period late) per 2 s session.
//   build/bin/vtb_bench_servo --benchmark_repetitions=3
#include "vtb/core/haptics/session.hh"

#include <benchmark/benchmark.h>

#include <atomic>
#include <filesystem>
#include <thread>

namespace {

void BM_servo_press_other_core_busy(benchmark::State& st) {
  vtb::Scene scene = vtb::read_scene(std::filesystem::path(VTB_SCENES_DIR) / "haptic_press.toml");
  scene.duration = 2.0;
  std::atomic<bool> stop{false};
  std::thread hog([&] {
    volatile double x = 0;
    while (!stop) x = x + 1.0;
  });
  vtb::HapticsReport r;
  for (auto _ : st) r = vtb::run_haptics(scene, vtb::HapticsOptions{});
  stop = true;
  hog.join();
  st.counters["rate_hz"] = r.rate_hz_mean;
  st.counters["period_p99_us"] = r.period_p99_us;
  st.counters["period_max_us"] = r.period_max_us;
  st.counters["deadline_misses"] = static_cast<double>(r.deadline_misses);
  st.counters["samples"] = static_cast<double>(r.samples);
}
BENCHMARK(BM_servo_press_other_core_busy)->Unit(benchmark::kMillisecond)->Iterations(1);

} // namespace

BENCHMARK_MAIN();
