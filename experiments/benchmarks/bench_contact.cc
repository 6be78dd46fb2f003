// 3D haptic contact on the canonical slabs: refitting the CGAL AABB tree to a new shape, the
// inside/outside ray-parity query, and one proxy update of a handle pressed into the top face.
//   build/bin/vtb_bench_contact --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "vtb/haptics/contact3d.hh"
#include "vtb/meshes/msh_io.hh"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

namespace {

vtb::Mesh3 slab(int nodes) {
  const auto file = std::filesystem::path(VTB_MESHES_DIR) / ("slab_" + std::to_string(nodes) + ".msh");
  return std::get<vtb::Mesh3>(vtb::read_msh(file));
}

/// The slab's shape a little displaced, so each rebuild sees new coordinates.
vtb::Nodal<3> displaced(const vtb::Mesh3& m, double s) {
  vtb::Nodal<3> x = m.points;
  x.row(2) += s * 1e-3 * x.row(0);
  return x;
}

/// Range 1 is the shape change in mm at the far end: 0.2 stays inside the boxes' margin (a refit:
/// copy and check), 20 does not (a full build every time).
void BM_tree_rebuild(benchmark::State& st) {
  const vtb::Mesh3 m = slab(static_cast<int>(st.range(0)));
  vtb::SurfaceTree tree(m);
  const double s = static_cast<double>(st.range(1));
  const vtb::Nodal<3> a = displaced(m, s), b = displaced(m, 2 * s);
  bool flip = false;
  for (auto _ : st) {
    tree.rebuild(flip ? a : b);
    flip = !flip;
  }
  st.counters["triangles"] = static_cast<double>(tree.facets().size());
  st.counters["builds"] = static_cast<double>(tree.builds());
}
BENCHMARK(BM_tree_rebuild)
    ->Args({500, 1})
    ->Args({500, 100})
    ->Args({2000, 1})
    ->Args({2000, 100})
    ->Unit(benchmark::kMicrosecond);

void BM_inside(benchmark::State& st) {
  const vtb::Mesh3 m = slab(static_cast<int>(st.range(0)));
  const vtb::SurfaceTree tree(m);
  for (auto _ : st) benchmark::DoNotOptimize(tree.inside(Eigen::Vector3d(0.1, 0.025, 0.015)));
}
BENCHMARK(BM_inside)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);

void BM_proxy_update_in_contact(benchmark::State& st) {
  const vtb::Mesh3 m = slab(static_cast<int>(st.range(0)));
  const vtb::SurfaceTree tree(m);
  vtb::SurfaceContact contact(tree);
  contact.update(Eigen::Vector3d(0.1, 0.025, 0.021), m.points);
  contact.update(Eigen::Vector3d(0.1, 0.025, 0.015), m.points); // contact begins
  for (auto _ : st) benchmark::DoNotOptimize(contact.update(Eigen::Vector3d(0.1, 0.025, 0.015), m.points));
}
BENCHMARK(BM_proxy_update_in_contact)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);

} // namespace

BENCHMARK_MAIN();
