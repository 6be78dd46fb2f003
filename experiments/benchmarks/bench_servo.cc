// Servo-loop timing of `vtb haptics` in real time, with the other core kept busy by a spinning
// thread (the worst case the issue names). Counters: mean rate, p99 and max period, deadline
// misses (cycles started more than half a period late), the servo cycle's own work (median, p99)
// per 2 s session; on the 2D press, the 3D slab press and the two-probe press.
//   build/bin/vtb_bench_servo --benchmark_repetitions=3
#include "vtb/haptics/session.hh"

#include <benchmark/benchmark.h>

#include <array>
#include <atomic>
#include <filesystem>
#include <thread>

namespace {

constexpr std::array<const char*, 3> kScenes = {"haptic_press", "haptic_slab_press", "haptic_two_probes"};

void BM_servo_press_other_core_busy(benchmark::State& st) {
  const std::string name = kScenes[static_cast<std::size_t>(st.range(0))];
  st.SetLabel(name);
  vtb::Scene scene = vtb::read_scene(std::filesystem::path(VTB_SCENES_DIR) / (name + ".toml"));
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
  st.counters["tick_median_us"] = r.tick_median_us;
  st.counters["tick_p99_us"] = r.tick_p99_us;
  st.counters["physics_step_us"] = r.physics_step_median_us;
}
BENCHMARK(BM_servo_press_other_core_busy)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->Iterations(1);

} // namespace

BENCHMARK_MAIN();
