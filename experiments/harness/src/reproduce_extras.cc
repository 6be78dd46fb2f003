#include "reproduce_parts.hh"
#include "vtb/core/solver_names.hh"

#include "vtb/core/output.hh"
#include "vtb/haptics/session.hh"
#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <malloc.h>
#include <ostream>
#include <sstream>
#include <thread>

namespace vtb::harness::parts {
namespace {

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "unknown";
}

/// Heap bytes in use (glibc), to measure what an integrator holds.
std::size_t heap_in_use() {
  return mallinfo2().uordblks;
}

template <int dim> std::string scaling_rows(const Scene& scene, const char* family, int steps) {
  std::ostringstream os;
  with_model(scene, [&](const auto& model) {
    if constexpr (std::decay_t<decltype(model)>::dimension == dim) {
      for (const char* solver : {solvers::kFilteredFull, solvers::kImplicitEuler}) {
        IntegratorOptions io = integrator_options(scene.solver);
        io.kind = solver == std::string(solvers::kImplicitEuler) ? solvers::kImplicitEuler : solvers::kFiltered;
        io.filter = solvers::kFilterFull;
        const std::size_t before = heap_in_use();
        const auto a = std::chrono::steady_clock::now();
        auto integ = make_integrator(model, io);
        const double pre = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
        const std::size_t bytes = heap_in_use() - before;
        State<dim> s = initial_state(model);
        std::vector<double> times;
        times.reserve(static_cast<std::size_t>(steps));
        for (int k = 0; k < steps; ++k) {
          const auto b = std::chrono::steady_clock::now();
          integ->step(s);
          times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - b).count());
        }
        const StepStats st = step_stats(std::move(times));
        os << family << ',' << dim << ',' << model.num_nodes() << ',' << model.net.num_springs() << ',' << solver << ','
           << std::setprecision(6) << pre * 1e3 << ',' << st.median * 1e6 << ',' << bytes / 1.0e6 << '\n';
      }
    }
  });
  return os.str();
}

std::string scaling_scene(int dim, int n) {
  std::ostringstream os;
  os << "[scene]\nname = \"scaling\"\nduration = 1.0\noutput_interval = 0.01\n[mesh]\n";
  if (dim == 2)
    os << "generate = { shape = \"rectangle\", size = [0.2, 0.05], divisions = [" << 4 * n << ", " << n << "] }\n";
  else
    os << "generate = { shape = \"box\", size = [0.2, 0.05, 0.05], divisions = [" << 4 * n << ", " << n << ", " << n
       << "] }\n";
  os << "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " << (dim == 2 ? "0.3333" : "0.25")
     << "\ndensity = 1000.0\n"
     << (dim == 2 ? "thickness = 0.001\n" : "") << "retardation_time = 2.0\n"
     << "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = "
     << (dim == 2 ? "[0.1, 0.0]" : "[0.1, 0.0, 0.0]") << "\n[solver]\nkind = \"filtered\"\ndt = 0.01\n";
  return os.str();
}

} // namespace

void write_meta(const std::filesystem::path& out, bool quick, double duration) {
  std::ostringstream os;
  os << "key,value\nquick," << (quick ? "true" : "false") << "\nduration_s," << duration << "\ncores,"
     << std::thread::hardware_concurrency() << "\ncpu,\"" << cpu_model() << "\"\n";
  write_files_atomically(out, {{"meta.csv", os.str()}});
}

void write_creep(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log) {
  if (log) *log << "[creep] strip against the Kelvin-Voigt law\n";
  const Scene scene = read_scene(scenes_dir / "creep_strip.toml");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  const double tau = scene.material.retardation_time;
  const double u_static = linear_static(model, scene.duration).col(model.probes.at(0).second)(0);
  const std::vector<std::string> solvers = {solvers::kFilteredFull, solvers::kImplicitEuler, solvers::kCvode};
  std::vector<Trajectory<2>> runs(solvers.size());
  for (std::size_t k = 0; k < solvers.size(); ++k) run_solver(scene, model, solvers[k], 0, runs[k]);
  std::ostringstream os;
  os << std::setprecision(8) << "t,analytic,filtered_full,implicit_euler,cvode\n";
  for (std::size_t j = 0; j < runs[0].t.size(); ++j) {
    const double t = runs[0].t[j];
    os << t << ',' << u_static * (1 - std::exp(-t / tau));
    for (const auto& r : runs) os << ',' << r.probe_u[j][0](0);
    os << '\n';
  }
  write_files_atomically(out, {{"creep.csv", os.str()}});
}

void write_transient(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log) {
  if (log) *log << "[transient] cantilever step: the filters' lag against CVODE\n";
  const Scene scene = read_scene(scenes_dir / "cantilever_step.toml");
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)));
  Trajectory<2> ref;
  run_solver(scene, model, solvers::kCvode, 0, ref); // rtol 1e-10 from the scene
  std::ostringstream os;
  os << std::setprecision(6) << "dt,solver,tip_error,step_median_us,stable\n";
  for (const double dt : {1e-3, 1e-2, 4e-2})
    for (const char* solver : {solvers::kFilteredFull, solvers::kFilteredTensor, solvers::kImplicitEuler}) {
      Trajectory<2> tr;
      const RunReport r = run_solver(scene, model, solver, dt, tr);
      // The tip's largest error over the samples relative to its peak (the scene's one probe).
      const double e = compare(tr, ref).probe_max;
      os << dt << ',' << solver << ',' << (r.stable ? e : std::nan("")) << ',' << 1e6 * r.step_seconds.median << ','
         << (r.stable ? "true" : "false") << '\n';
    }
  write_files_atomically(out, {{"transient.csv", os.str()}});
}

void write_haptics(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, double stall_time,
                   std::ostream* log) {
  if (log) *log << "[haptics] real-time session with a physics stall at " << stall_time << " s\n";
  const Scene scene = read_scene(scenes_dir / "haptic_press.toml");
  HapticsOptions ho;
  ho.fault = HapticsOptions::Fault::stall;
  ho.fault_time = stall_time;
  const HapticsReport r = run_haptics(scene, ho);
  std::ostringstream periods, trace, summary;
  periods << std::setprecision(6) << "period_us\n";
  for (double p : r.period_us) periods << p << '\n';
  trace << std::setprecision(6) << "t,hy,fx,fy,force\n";
  const ProbeTrace& p = r.probes.at(0);
  for (std::size_t k = 0; k < r.t.size(); ++k)
    trace << r.t[k] << ',' << p.hy[k] << ',' << p.fx[k] << ',' << p.fy[k] << ',' << std::hypot(p.fx[k], p.fy[k])
          << '\n';
  summary << std::setprecision(6)
          << "rate_hz,period_p99_us,period_max_us,deadline_misses,samples,stall_time,fault_time,"
          << "force_zero_time,max_force,device_limit\n"
          << r.rate_hz_mean << ',' << r.period_p99_us << ',' << r.period_max_us << ',' << r.deadline_misses << ','
          << r.samples << ',' << stall_time << ',' << r.fault_time << ',' << r.force_zero_time << ',' << r.max_force
          << ',' << scene.haptics->max_force << '\n';
  write_files_atomically(out, {{"haptics_periods.csv", periods.str()},
                               {"haptics_trace.csv", trace.str()},
                               {"haptics_summary.csv", summary.str()}});
}

void write_scaling(const std::filesystem::path& out, bool quick, std::ostream* log) {
  std::ostringstream os;
  os << "family,dim,nodes,springs,solver,precompute_ms,step_median_us,heap_mb\n";
  const std::vector<int> ladder2 = quick ? std::vector<int>{4, 8, 16, 32} : std::vector<int>{4, 8, 16, 32, 64};
  const std::vector<int> ladder3 = quick ? std::vector<int>{2, 3, 4, 6} : std::vector<int>{2, 3, 4, 6, 8, 12};
  const int steps = quick ? 20 : 50;
  for (int n : ladder2) {
    if (log) *log << "[scaling] rectangle " << 4 * n << " x " << n << "\n";
    os << scaling_rows<2>(parse_scene(scaling_scene(2, n), "scaling-2d", "."), "rectangle", steps);
  }
  for (int n : ladder3) {
    if (log) *log << "[scaling] box " << 4 * n << " x " << n << " x " << n << "\n";
    os << scaling_rows<3>(parse_scene(scaling_scene(3, n), "scaling-3d", "."), "box", steps);
  }
  write_files_atomically(out, {{"scaling.csv", os.str()}});
}

} // namespace vtb::harness::parts
