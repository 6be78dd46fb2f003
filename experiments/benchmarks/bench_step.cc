// Step cost of each spring integrator on the paper's mesh sizes (structured stand-ins until
// the CGAL plates land: 126 ~ 123 nodes, exactly 517 nodes) and on 3D boxes, plus the W
// precompute. Run: build/bin/vtb_bench_step --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true  (medians are what the closing notes quote).
#include "vtb/linalg/block_multigrid.hh"
#include "vtb/linalg/nodal_solve.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"
#include "vtb/solvers/implicit_euler_cg.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/solvers/tensor_filter.hh"
#include "vtb/springs/fitted_springs.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/cgal_generate.hh"
#endif

#include <Eigen/CholmodSupport>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>

namespace vtb {
namespace {

/// A plate 0.2 x 0.05 (or a box 0.2 x 0.05 x 0.05) clamped at x = 0, pulled at x = max; with
/// `clamped` false a free body pulled at one end (where the momentum correction acts).
template <int dim>
Model<dim> bench_model(const Eigen::Matrix<int, dim, 1>& div, bool clamped = true, const Mesh<dim>* mesh = nullptr,
                       const char* springs = "lloyd") {
  Scene s;
  s.file = "bench";
  s.duration = 1.0;
  s.output_interval = 0.01;
  s.material = MaterialDesc{5.0e4, 0.3333, 1000.0, 0.001, 0.05, 0.0};
  s.solver.springs = springs;
  FixDesc fix;
  fix.region.group = "left";
  fix.region.label = "clamp";
  if (clamped) s.fixes.push_back(fix);
  LoadDesc load;
  load.region.group = "right";
  load.region.label = "pull";
  load.total_force = Eigen::VectorXd::Zero(dim);
  load.total_force[0] = 0.5;
  s.loads.push_back(load);
  if (mesh) return build_model<dim>(s, *mesh);
  if constexpr (dim == 2)
    return build_model<2>(s, generate_rectangle({0.2, 0.05}, div));
  else
    return build_model<3>(s, generate_box({0.2, 0.05, 0.05}, div));
}

/// One integrator stepping on its own state from a warmed-up start, put back there every 1000
/// steps so that the state stays in the same regime.
template <int dim> struct Stepper {
  std::unique_ptr<Integrator<dim>> integ;
  State<dim> s, saved;
  long n = 0;
  Stepper(const Model<dim>& model, const std::string& kind, const std::string& filter, bool correct = true) {
    IntegratorOptions o;
    o.kind = kind;
    o.filter = filter;
    o.momentum_correction = correct;
    o.dt = kind == solvers::kExplicit ? 0.5 * explicit_critical_dt(max_omega_squared(model, false), 0.05, 0.0) : 1e-3;
    integ = make_integrator(model, o);
    s = initial_state(model);
    for (int k = 0; k < 10; ++k) integ->step(s); // warm up
    saved = s;
  }
  /// One step; true when the state is due to be put back (put_back(), outside any clock).
  bool step() {
    integ->step(s);
    return ++n % 1000 == 0;
  }
  void put_back() { s = saved; }
  /// Seconds for `steps` steps.
  double run(int steps) {
    double t = 0;
    for (int k = 0; k < steps; ++k) {
      const auto a = std::chrono::steady_clock::now();
      const bool due = step();
      t += std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
      if (due) put_back();
    }
    return t;
  }
};

template <int dim>
void run_steps(benchmark::State& st, const Model<dim>& model, const std::string& kind, const std::string& filter,
               bool correct = true) {
  Stepper<dim> stepper(model, kind, filter, correct);
  const auto* cg = dynamic_cast<const ImplicitEulerCG<dim>*>(stepper.integ.get());
  const auto* filtered = dynamic_cast<const FilteredImplicit<dim>*>(stepper.integ.get());
  const long extra_before = filtered ? filtered->extra_corrections() : 0;
  long iterations = 0;
  for (auto _ : st) {
    const bool due = stepper.step();
    if (cg) iterations += cg->last_iterations();
    if (due) {
      st.PauseTiming();
      stepper.put_back();
      st.ResumeTiming();
    }
  }
  st.counters["nodes"] = model.num_nodes();
  st.counters["springs"] = model.net.num_springs();
  st.counters["dt"] = stepper.integ->dt();
  if (cg) st.counters["cg_iterations"] = static_cast<double>(iterations) / static_cast<double>(stepper.n);
  // The tensor filter's conjugate-gradient steps past its one correction, per step (each one
  // more V-cycle).
  if (filtered)
    st.counters["extra_corrections"] =
        static_cast<double>(filtered->extra_corrections() - extra_before) / static_cast<double>(stepper.n);
}

const Model<2>& plate126() {
  static const Model<2> m = bench_model<2>(Eigen::Vector2i(20, 5));
  return m;
}
const Model<2>& plate517() {
  static const Model<2> m = bench_model<2>(Eigen::Vector2i(46, 10));
  return m;
}
const Model<2>& free_plate517() {
  static const Model<2> m = bench_model<2>(Eigen::Vector2i(46, 10), false);
  return m;
}
const Model<3>& box275() {
  static const Model<3> m = bench_model<3>(Eigen::Vector3i(10, 4, 4));
  return m;
}
const Model<3>& box1701() {
  static const Model<3> m = bench_model<3>(Eigen::Vector3i(20, 8, 8));
  return m;
}

#define VTB_STEP_BENCH(MESH, KIND, FILTER, NAME)                                                                       \
  void BM_step_##MESH##_##NAME(benchmark::State& st) {                                                                 \
    run_steps(st, MESH(), KIND, FILTER);                                                                               \
  }                                                                                                                    \
  BENCHMARK(BM_step_##MESH##_##NAME)->Unit(benchmark::kMicrosecond);

VTB_STEP_BENCH(plate126, solvers::kExplicit, "", explicit)
VTB_STEP_BENCH(plate126, solvers::kFiltered, solvers::kFilterNeighbors, filtered_neighbors)
VTB_STEP_BENCH(plate126, solvers::kFiltered, solvers::kFilterFull, filtered_full)
VTB_STEP_BENCH(plate126, solvers::kImplicitEuler, "", implicit_euler)
VTB_STEP_BENCH(plate517, solvers::kExplicit, "", explicit)
VTB_STEP_BENCH(plate517, solvers::kFiltered, solvers::kFilterNeighbors, filtered_neighbors)
VTB_STEP_BENCH(plate517, solvers::kFiltered, solvers::kFilterFull, filtered_full)
VTB_STEP_BENCH(plate517, solvers::kImplicitEuler, "", implicit_euler)
VTB_STEP_BENCH(plate517, solvers::kFiltered, solvers::kFilterTensor, filtered_tensor)

/// Issue 26's ratios in one process: filter `a`'s step over filter `b`'s, timed in alternating
/// rounds of `steps` steps each, so that both see the same minute of a machine whose speed
/// drifts (separate benchmarks a few seconds apart differed by up to 1.4x). Counters: each
/// filter's median step over the rounds (us) and the median of the rounds' ratios.
template <int dim>
void paired_ratio(benchmark::State& st, const Model<dim>& model_a, const Model<dim>& model_b, const std::string& a,
                  const std::string& b, int steps) {
  Stepper<dim> sa(model_a, solvers::kFiltered, a), sb(model_b, solvers::kFiltered, b);
  std::vector<double> ta, tb, ratio;
  for (auto _ : st) {
    const double x = sa.run(steps), y = sb.run(steps);
    ta.push_back(1e6 * x / steps);
    tb.push_back(1e6 * y / steps);
    ratio.push_back(x / y);
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  st.counters["a_us"] = median(ta);
  st.counters["b_us"] = median(tb);
  st.counters["ratio"] = median(ratio);
}

template <int dim>
void paired_ratio(benchmark::State& st, const Model<dim>& model, const std::string& a, const std::string& b,
                  int steps) {
  paired_ratio(st, model, model, a, b, steps);
}

/// The tensor filter's step over the full filter's on the 517-node plate (goal: at most 2).
void BM_ratio_plate517_tensor_over_full(benchmark::State& st) {
  paired_ratio(st, plate517(), solvers::kFilterTensor, solvers::kFilterFull, 100);
}

/// The volume term's cost (issue 72's goal: at most 1.3): the full filter's step on the plate
/// with springs = "volume" over the same step with the springs alone, in one run.
void BM_ratio_plate517_volume_over_springs(benchmark::State& st) {
  static const Model<2> volume = bench_model<2>(Eigen::Vector2i(46, 10), true, nullptr, "volume");
  paired_ratio(st, volume, plate517(), solvers::kFilterFull, solvers::kFilterFull, 100);
}
BENCHMARK(BM_ratio_plate517_volume_over_springs)->Unit(benchmark::kMillisecond)->Iterations(200);
/// The same with the stable energy's shear part in every cell (`springs = "fitted-stable"`'s
/// term; the element fit's constants and half the shear modulus, no fit: the step's work is the
/// same whatever the constants).
template <int dim> Model<dim> with_cell_shear(Model<dim> m) {
  const MaterialDesc mat{5.0e4, 0.3333, 1000.0, 0.001, 0.05, 0.0}; // bench_model's
  set_cell_shear(m.net.volume, mat.young_modulus / (2 * (1 + mat.poisson_ratio)), kStableCellShear, mat.thickness,
                 mat.retardation_time);
  return m;
}
void BM_ratio_plate517_stable_over_springs(benchmark::State& st) {
  static const Model<2> stable = with_cell_shear(bench_model<2>(Eigen::Vector2i(46, 10), true, nullptr, "volume"));
  paired_ratio(st, stable, plate517(), solvers::kFilterFull, solvers::kFilterFull, 100);
}
BENCHMARK(BM_ratio_plate517_stable_over_springs)->Unit(benchmark::kMillisecond)->Iterations(200);
/// And with the volume averaged per node (`springs = "fitted-nodal"`'s term: the shear part,
/// mu V per cell, the rest of the element fit's constants per node; no fit, as above).
template <int dim> Model<dim> with_nodal_volume(Model<dim> m) {
  m = with_cell_shear(std::move(m));
  const MaterialDesc mat{5.0e4, 0.3333, 1000.0, 0.001, 0.05, 0.0}; // bench_model's
  const Eigen::VectorXd own =
      modulus_times_volume(m.net.volume, mat.young_modulus / (2 * (1 + mat.poisson_ratio)), mat.thickness);
  make_nodal_volumes(m.net.volume, m.net.num_nodes(), &own);
  return m;
}
void BM_ratio_plate517_nodal_over_springs(benchmark::State& st) {
  static const Model<2> nodal = with_nodal_volume(bench_model<2>(Eigen::Vector2i(46, 10), true, nullptr, "volume"));
  paired_ratio(st, nodal, plate517(), solvers::kFilterFull, solvers::kFilterFull, 100);
}
BENCHMARK(BM_ratio_plate517_nodal_over_springs)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_ratio_plate517_tensor_over_full)->Unit(benchmark::kMillisecond)->Iterations(200);

/// The torque correction's cost: the full filter's step on a free plate with and without it.
void BM_step_free_plate517_filtered_full_corrected(benchmark::State& st) {
  run_steps(st, free_plate517(), solvers::kFiltered, solvers::kFilterFull, true);
}
void BM_step_free_plate517_filtered_full_uncorrected(benchmark::State& st) {
  run_steps(st, free_plate517(), solvers::kFiltered, solvers::kFilterFull, false);
}
BENCHMARK(BM_step_free_plate517_filtered_full_corrected)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_step_free_plate517_filtered_full_uncorrected)->Unit(benchmark::kMicrosecond);
VTB_STEP_BENCH(box275, solvers::kExplicit, "", explicit)
VTB_STEP_BENCH(box275, solvers::kFiltered, solvers::kFilterNeighbors, filtered_neighbors)
VTB_STEP_BENCH(box275, solvers::kFiltered, solvers::kFilterFull, filtered_full)
VTB_STEP_BENCH(box275, solvers::kImplicitEuler, "", implicit_euler)
VTB_STEP_BENCH(box1701, solvers::kFiltered, solvers::kFilterNeighbors, filtered_neighbors)
VTB_STEP_BENCH(box1701, solvers::kFiltered, solvers::kFilterFull, filtered_full)
VTB_STEP_BENCH(box1701, solvers::kFiltered, solvers::kFilterTensor, filtered_tensor)
VTB_STEP_BENCH(box1701, solvers::kFiltered, solvers::kFilterTensorMultigrid, filtered_tensor_multigrid)
VTB_STEP_BENCH(box1701, solvers::kFiltered, solvers::kFilterMultigrid, filtered_multigrid)
VTB_STEP_BENCH(box1701, solvers::kImplicitEuler, "", implicit_euler)

#ifdef VTB_HAVE_CGAL_MESHERS
/// The performance issue's 10k-node case: a CGAL Mesh_3 slab 0.2 x 0.05 x 0.02 of about 10,000
/// nodes (9,864), clamped at one end and pulled at the other.
const Model<3>& slab10k() {
  static const Mesh3 mesh = mesh_solid("slab", 10000);
  static const Model<3> m = bench_model<3>(Eigen::Vector3i::Zero(), true, &mesh);
  return m;
}
VTB_STEP_BENCH(slab10k, solvers::kFiltered, solvers::kFilterFull, filtered_full)
VTB_STEP_BENCH(slab10k, solvers::kFiltered, solvers::kFilterMultigrid, filtered_multigrid)
VTB_STEP_BENCH(slab10k, solvers::kFiltered, solvers::kFilterTensorMultigrid, filtered_tensor_multigrid)
VTB_STEP_BENCH(slab10k, solvers::kImplicitEuler, "", implicit_euler)
/// tensor-multigrid's step over the scalar V-cycle's on the 10k slab (goal: at most 2).
void BM_ratio_slab10k_tensor_multigrid_over_multigrid(benchmark::State& st) {
  paired_ratio(st, slab10k(), solvers::kFilterTensorMultigrid, solvers::kFilterMultigrid, 5);
}
BENCHMARK(BM_ratio_slab10k_tensor_multigrid_over_multigrid)->Unit(benchmark::kMillisecond)->Iterations(40);

/// The volume term's cost on the slab: multigrid (what auto runs with the term) with and
/// without it, in one run.
void BM_ratio_slab10k_volume_over_springs(benchmark::State& st) {
  static const Mesh3 mesh = mesh_solid("slab", 10000);
  static const Model<3> volume = bench_model<3>(Eigen::Vector3i::Zero(), true, &mesh, "volume");
  paired_ratio(st, volume, slab10k(), solvers::kFilterMultigrid, solvers::kFilterMultigrid, 5);
}
BENCHMARK(BM_ratio_slab10k_volume_over_springs)->Unit(benchmark::kMillisecond)->Iterations(40);
void BM_ratio_slab10k_stable_over_springs(benchmark::State& st) {
  static const Mesh3 mesh = mesh_solid("slab", 10000);
  static const Model<3> stable = with_cell_shear(bench_model<3>(Eigen::Vector3i::Zero(), true, &mesh, "volume"));
  paired_ratio(st, stable, slab10k(), solvers::kFilterMultigrid, solvers::kFilterMultigrid, 5);
}
BENCHMARK(BM_ratio_slab10k_stable_over_springs)->Unit(benchmark::kMillisecond)->Iterations(40);
void BM_ratio_slab10k_nodal_over_springs(benchmark::State& st) {
  static const Mesh3 mesh = mesh_solid("slab", 10000);
  static const Model<3> nodal = with_nodal_volume(bench_model<3>(Eigen::Vector3i::Zero(), true, &mesh, "volume"));
  paired_ratio(st, nodal, slab10k(), solvers::kFilterMultigrid, solvers::kFilterMultigrid, 5);
}
BENCHMARK(BM_ratio_slab10k_nodal_over_springs)->Unit(benchmark::kMillisecond)->Iterations(40);
/// What a scene with no filter key runs (auto: the V-cycle at this size).
VTB_STEP_BENCH(slab10k, solvers::kFiltered, solvers::kFilterAuto, filtered_auto)

/// The spring fit (springs = "fitted" or "auto", no cache, the default options: at this size
/// the early stop on the held-out modes) on the clamped slab, on its supports. One iteration:
/// it takes tens of seconds.
void BM_precompute_fit_springs_slab10k(benchmark::State& st) {
  const Model<3>& m = slab10k();
  FitOptions o;
  for (int v = 0; v < m.num_nodes(); ++v)
    if (m.constrained[static_cast<std::size_t>(v)]) o.supports.push_back(v);
  for (auto _ : st) benchmark::DoNotOptimize(fitted_stiffness(m.mesh, 1.0, 0.25, 1.0, o));
}
BENCHMARK(BM_precompute_fit_springs_slab10k)->Unit(benchmark::kSecond)->Iterations(1);
#endif

// The filtered step's kernels alone, on the 517-node plate and the 1701-node box: the spring
// forces (a mid-run state), the solve with H's factor for all coordinates at once (nodal
// layout, docs/performance.md) against Eigen's triangular solves one coordinate at a time.
template <int dim> State<dim> midrun_state(const Model<dim>& model) {
  IntegratorOptions o;
  auto integ = make_integrator(model, o);
  State<dim> s = initial_state(model);
  for (int k = 0; k < 50; ++k) integ->step(s);
  return s;
}

template <int dim> void spring_forces(benchmark::State& st, const Model<dim>& model) {
  const State<dim> s = midrun_state(model);
  Nodal<dim> f = Nodal<dim>::Zero(dim, model.num_nodes());
  for (auto _ : st) {
    add_internal_forces(model.net, s.u, s.v, f, 1e-3);
    benchmark::DoNotOptimize(f.data());
  }
  st.counters["springs"] = model.net.num_springs();
}
void BM_kernel_forces_plate517(benchmark::State& st) {
  spring_forces(st, plate517());
}
void BM_kernel_forces_box1701(benchmark::State& st) {
  spring_forces(st, box1701());
}
BENCHMARK(BM_kernel_forces_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_forces_box1701)->Unit(benchmark::kMicrosecond);

/// The volume term's force pass alone (add_volume_forces, the chunked kernel of
/// cell_volumes.cc) on the same meshes, beside BM_kernel_forces_* (the springs' pass).
template <int dim> void volume_forces(benchmark::State& st, const Model<dim>& model) {
  const State<dim> s = midrun_state(model);
  Nodal<dim> f = Nodal<dim>::Zero(dim, model.num_nodes());
  for (auto _ : st) {
    add_volume_forces(model.net.volume, model.net.rest, s.u, s.v, f, 1e-3);
    benchmark::DoNotOptimize(f.data());
  }
  st.counters["cells"] = model.net.volume.size();
}
void BM_kernel_volume_forces_plate517(benchmark::State& st) {
  static const Model<2> volume = bench_model<2>(Eigen::Vector2i(46, 10), true, nullptr, "volume");
  volume_forces(st, volume);
}
void BM_kernel_volume_forces_box1701(benchmark::State& st) {
  static const Model<3> volume = bench_model<3>(Eigen::Vector3i(20, 8, 8), true, nullptr, "volume");
  volume_forces(st, volume);
}
BENCHMARK(BM_kernel_volume_forces_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_volume_forces_box1701)->Unit(benchmark::kMicrosecond);

/// The 2D tensor filter's force pass: the forces and the springs' turns its rotations read
/// (add_internal_forces_and_turns), against BM_kernel_forces_plate517 alone.
void BM_kernel_forces_and_turns_plate517(benchmark::State& st) {
  const Model<2>& model = plate517();
  const State<2> s = midrun_state(model);
  TensorFilter<2> filter(model, 1e-3);
  Nodal<2> f = Nodal<2>::Zero(2, model.num_nodes());
  for (auto _ : st) {
    add_internal_forces_and_turns(model.net, s.u, s.v, f, 1e-3, filter.turns());
    benchmark::DoNotOptimize(f.data());
  }
}
BENCHMARK(BM_kernel_forces_and_turns_plate517)->Unit(benchmark::kMicrosecond);

template <int dim> void solve(benchmark::State& st, const Model<dim>& model, bool nodal) {
  OrderedLDLT factor(filter_system_matrix(model, 1e-3));
  factor.factorize();
  const NodalSolve fast(factor);
  const auto n = factor.size();
  const Nodal<dim> rhs = Nodal<dim>::Random(dim, n);
  Nodal<dim> x = rhs;
  Eigen::MatrixXd y = rhs.transpose();
  for (auto _ : st) {
    if (nodal) {
      x = rhs;
      fast.solve_in_place<dim>(x);
      benchmark::DoNotOptimize(x.data());
    } else {
      y = rhs.transpose();
      factor.solve_in_place(y);
      benchmark::DoNotOptimize(y.data());
    }
  }
  st.counters["L_nonzeros"] = static_cast<double>(fast.factor_nonzeros());
}
void BM_kernel_solve_nodal_plate517(benchmark::State& st) {
  solve(st, plate517(), true);
}
void BM_kernel_solve_eigen_plate517(benchmark::State& st) {
  solve(st, plate517(), false);
}
void BM_kernel_solve_nodal_box1701(benchmark::State& st) {
  solve(st, box1701(), true);
}
void BM_kernel_solve_eigen_box1701(benchmark::State& st) {
  solve(st, box1701(), false);
}
BENCHMARK(BM_kernel_solve_nodal_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_solve_eigen_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_solve_nodal_box1701)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_solve_eigen_box1701)->Unit(benchmark::kMicrosecond);

// The tensor filter's two per-step kernels on a mid-run state: prepare (each node's rotation
// and the springs' direction mismatch; in 2D what the step runs after its force pass made the
// turns, prepare_turned, so forces_and_turns + prepare is the step's share) and the solve with
// its H (node-ordered factor, tile by tile, with the rotations applied), beside the forces and
// the scalar solve above.
template <int dim> void tensor_kernel(benchmark::State& st, const Model<dim>& model, bool prepare) {
  const State<dim> s = midrun_state(model);
  TensorFilter<dim> filter(model, 1e-3);
  filter.prepare(s.u);
  if constexpr (dim == 2) { // the step's force pass, once: prepare_turned reads its turns
    Nodal<2> forces = Nodal<2>::Zero(2, model.num_nodes());
    add_internal_forces_and_turns(model.net, s.u, s.v, forces, 1e-3, filter.turns());
  }
  const Nodal<dim> f = Nodal<dim>::Random(dim, model.num_nodes());
  Nodal<dim> dv(dim, static_cast<Eigen::Index>(model.free_nodes.size()));
  const CouplingSet<dim> none(model.free_index); // no couplings
  for (auto _ : st) {
    if (prepare) {
      // 2D: normalising the turns' sums in place leaves unit pairs, which normalise to
      // themselves, so each iteration does the step's work on the same values.
      benchmark::DoNotOptimize(dim == 2 ? filter.prepare_turned(s.u) : filter.prepare(s.u));
    } else {
      filter.solve(f, none, 1e-3, dv);
      benchmark::DoNotOptimize(dv.data());
    }
  }
}
void BM_kernel_tensor_prepare_plate517(benchmark::State& st) {
  tensor_kernel(st, plate517(), true);
}
void BM_kernel_tensor_solve_plate517(benchmark::State& st) {
  tensor_kernel(st, plate517(), false);
}
void BM_kernel_tensor_prepare_box1701(benchmark::State& st) {
  tensor_kernel(st, box1701(), true);
}
void BM_kernel_tensor_solve_box1701(benchmark::State& st) {
  tensor_kernel(st, box1701(), false);
}
BENCHMARK(BM_kernel_tensor_prepare_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_tensor_solve_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_tensor_prepare_box1701)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_tensor_solve_box1701)->Unit(benchmark::kMicrosecond);
// A 3D factor whose tiles stay in L2 (the 1,701-node box's 10 MB of tiles per sweep do not):
// the sweeps' own speed, beside BM_step_box275_filtered_full.
void BM_kernel_tensor_solve_box275(benchmark::State& st) {
  tensor_kernel(st, box275(), false);
}
BENCHMARK(BM_kernel_tensor_solve_box275)->Unit(benchmark::kMicrosecond);
VTB_STEP_BENCH(box275, solvers::kFiltered, solvers::kFilterTensor, filtered_tensor)

// CHOLMOD's supernodal Cholesky of the same H (Eigen's CholmodSupernodalLLT, CHOLMOD's own
// ordering), against OrderedLDLT (Eigen's simplicial LDL^T, AMD) with the nodal solve: the
// factorisation (the filter's precompute) and the solve of all coordinates (its step).
template <int dim> void factor_cholmod(benchmark::State& st, const Model<dim>& model) {
  const Eigen::SparseMatrix<double> H = filter_system_matrix(model, 1e-3);
  for (auto _ : st) {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt(H);
    benchmark::DoNotOptimize(llt.info());
  }
}
template <int dim> void factor_simplicial(benchmark::State& st, const Model<dim>& model) {
  const Eigen::SparseMatrix<double> H = filter_system_matrix(model, 1e-3);
  for (auto _ : st) {
    OrderedLDLT factor(H);
    benchmark::DoNotOptimize(factor.factorize());
  }
}
template <int dim> void solve_cholmod(benchmark::State& st, const Model<dim>& model) {
  const Eigen::SparseMatrix<double> H = filter_system_matrix(model, 1e-3);
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt(H);
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(H.rows(), dim);
  Eigen::MatrixXd x(H.rows(), dim);
  for (auto _ : st) {
    x = llt.solve(rhs); // CHOLMOD allocates its result: fine for a kernel benchmark
    benchmark::DoNotOptimize(x.data());
  }
}
void BM_kernel_solve_cholmod_plate517(benchmark::State& st) {
  solve_cholmod(st, plate517());
}
void BM_kernel_solve_cholmod_box1701(benchmark::State& st) {
  solve_cholmod(st, box1701());
}
void BM_precompute_factor_cholmod_box1701(benchmark::State& st) {
  factor_cholmod(st, box1701());
}
void BM_precompute_factor_simplicial_box1701(benchmark::State& st) {
  factor_simplicial(st, box1701());
}
BENCHMARK(BM_kernel_solve_cholmod_plate517)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_solve_cholmod_box1701)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_precompute_factor_cholmod_box1701)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_precompute_factor_simplicial_box1701)->Unit(benchmark::kMillisecond);
#ifdef VTB_HAVE_CGAL_MESHERS
void BM_kernel_solve_nodal_slab10k(benchmark::State& st) {
  solve(st, slab10k(), true);
}
void BM_kernel_solve_cholmod_slab10k(benchmark::State& st) {
  solve_cholmod(st, slab10k());
}
void BM_precompute_factor_cholmod_slab10k(benchmark::State& st) {
  factor_cholmod(st, slab10k());
}
void BM_precompute_factor_simplicial_slab10k(benchmark::State& st) {
  factor_simplicial(st, slab10k());
}
/// The tensor-multigrid filter's kernels: one block V-cycle, and the refresh after the cover
/// changed H's values (the diagonal inverses, the Galerkin products, the coarsest factor).
BlockMultigrid<3> tensor_cycle(const Model<3>& m) {
  Nodal<3> x(3, static_cast<Eigen::Index>(m.free_nodes.size()));
  for (Eigen::Index a = 0; a < x.cols(); ++a) x.col(a) = m.net.rest.col(m.free_nodes[static_cast<std::size_t>(a)]);
  return BlockMultigrid<3>(tensor_filter_matrix(m, 1e-3), x);
}
void BM_kernel_tensor_vcycle_slab10k(benchmark::State& st) {
  BlockMultigrid<3> mg = tensor_cycle(slab10k());
  const auto n = static_cast<std::size_t>(slab10k().free_nodes.size()) * BlockMultigrid<3>::kLanes;
  std::vector<double> b(n, 0.0), x(n);
  for (std::size_t k = 0; k < n; ++k) b[k] = k % 4 == 3 ? 0.0 : std::sin(0.1 * static_cast<double>(k));
  for (auto _ : st) {
    mg.apply(b.data(), x.data());
    benchmark::DoNotOptimize(x.data());
  }
  std::string sizes;
  for (const Eigen::Index l : mg.level_sizes()) sizes += (sizes.empty() ? "nodes " : " ") + std::to_string(l);
  st.SetLabel(sizes);
  st.counters["MB"] = static_cast<double>(mg.memory_bytes()) / 1e6;
}
void BM_kernel_tensor_refresh_slab10k(benchmark::State& st) {
  BlockMultigrid<3> mg = tensor_cycle(slab10k());
  for (auto _ : st) mg.refresh();
}
void BM_precompute_tensor_vcycle_slab10k(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(tensor_cycle(slab10k()).levels());
}
BENCHMARK(BM_kernel_tensor_vcycle_slab10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_tensor_refresh_slab10k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_precompute_tensor_vcycle_slab10k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_kernel_solve_nodal_slab10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_kernel_solve_cholmod_slab10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_precompute_factor_cholmod_slab10k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_precompute_factor_simplicial_slab10k)->Unit(benchmark::kMillisecond);
#endif

void BM_precompute_plate517_neighbors(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(filter_matrix_neighbors(plate517(), 1e-3));
}
BENCHMARK(BM_precompute_plate517_neighbors)->Unit(benchmark::kMillisecond);

void BM_precompute_plate517_full_factor(benchmark::State& st) {
  IntegratorOptions o;
  o.kind = solvers::kFiltered;
  o.filter = solvers::kFilterFull;
  for (auto _ : st) benchmark::DoNotOptimize(make_integrator(plate517(), o));
}
BENCHMARK(BM_precompute_plate517_full_factor)->Unit(benchmark::kMillisecond);

} // namespace
} // namespace vtb

BENCHMARK_MAIN();
