#include "reproduce_parts.hh"
#include "vtb/problem/solver_names.hh"

#include "vtb/haptics/session.hh"
#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/cgal_generate.hh"
#endif
#include "vtb/base/input_error.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/problem/output.hh"
#include "vtb/problem/problem.hh"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <thread>
#include <variant>

namespace vtb::reproduction::parts {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables
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

} // namespace

void write_meta(const std::filesystem::path& out, bool quick, double duration, const std::string& binding) {
  std::ostringstream os;
  os << "key,value\nquick," << (quick ? "true" : "false") << "\nduration_s," << duration << "\ncores,"
     << std::thread::hardware_concurrency() << "\ncpu,\"" << cpu_model() << "\"\nbinding,\"" << binding << "\"\n";
  write_files_atomically(out, {{"meta.csv", os.str()}});
}

void write_creep(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log) {
  if (log) *log << "[creep] strip against the Kelvin-Voigt law\n";
  const Scene scene = read_scene(scenes_dir / "creep_strip.toml");
  const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb run builds them
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)), {}, true, &yardstick);
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
  const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb run builds them
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)), {}, true, &yardstick);
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

void write_tip_force(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, bool quick,
                     std::ostream* log) {
  if (log) *log << "[tip] the slab press held at each depth: two meshes, a 4 mm tip and a point proxy\n";
  const Scene base = read_scene(scenes_dir / "haptic_slab_press.toml");
  const double top = 0.02; // the slab's top face (z), which the hand's waypoints press into
  const std::vector<double> depths =
      quick ? std::vector<double>{0.002, 0.005} : std::vector<double>{0.001, 0.002, 0.003, 0.004, 0.005};
  const HapticsDesc& h = *base.haptics;
  // The half-space under a uniform disc of the tip's radius (mean compliance 16 (1 - nu^2) /
  // (3 pi^2 E a)) in series with the coupling and the hand's grip: a layer on a rigid base is
  // stiffer, so the force lies above it.
  const double a = 0.004, nu = base.material.poisson_ratio;
  const double half_space = 16 * (1 - nu * nu) / (3 * M_PI * M_PI * base.material.young_modulus * a);
  const double chain = 1 / h.coupling_stiffness + 1 / h.hand->grip_stiffness + half_space;
  const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb haptics builds them
  std::ostringstream os;
  os << std::setprecision(6) << "mesh,nodes,tip_radius,depth,force\n";
  for (double d : depths) os << "half-space,0," << a << ',' << d << ',' << d / chain << '\n';
  for (const char* mesh : {"slab_500.msh", "slab_2000.msh"})
    for (double tip : {a, 0.0})
      for (double d : depths) {
        Scene s = base;
        s.mesh.file = base.mesh.file.parent_path() / mesh;
        s.haptics->tip_radius = tip;
        s.duration = 1.8; // the hand reaches the depth at 1 s and holds it to 2 s
        s.haptics->hand->waypoints = {Eigen::Vector2d(0.1, 0.05), Eigen::Vector2d(0.1, top - d),
                                      Eigen::Vector2d(0.1, top - d), Eigen::Vector2d(0.1, 0.05)};
        HapticsOptions ho;
        ho.lockstep = true;
        ho.yardstick = &yardstick;
        const HapticsReport r = run_haptics(s, ho);
        double sum = 0;
        int n = 0;
        for (std::size_t k = 0; k < r.t.size(); ++k)
          if (r.t[k] >= 1.3) sum += r.probes.at(0).fy[k], ++n;
        const auto nodes = std::visit([](const auto& m) { return m.num_nodes(); }, load_mesh(s));
        os << mesh << ',' << nodes << ',' << tip << ',' << d << ',' << sum / std::max(n, 1) << '\n';
      }
  write_files_atomically(out, {{"tip_force.csv", os.str()}});
}

void write_haptics(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, double stall_time,
                   std::ostream* log) {
  if (log) *log << "[haptics] real-time session with a physics stall at " << stall_time << " s\n";
  // The paper's filter (its W), named, so that a change of the default (auto) leaves the
  // reproduction's haptic trace as it is.
  Scene scene = read_scene(scenes_dir / "haptic_press.toml");
  scene.solver.step.filter = solvers::kFilterFull;
  HapticsOptions ho;
  const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb haptics builds them
  ho.yardstick = &yardstick;
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

namespace {

/// A session's force magnitude while the hand holds still (t in [1.3, 1.8] s): its mean and the
/// largest change between two consecutive servo cycles.
std::pair<double, double> held_force(const HapticsReport& r) {
  const ProbeTrace& p = r.probes.at(0);
  double sum = 0, largest = 0, last = NAN;
  int n = 0;
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    if (r.t[k] < 1.3 || r.t[k] > 1.8) continue;
    const double f = std::hypot(p.fx[k], p.fy[k]);
    sum += f, ++n;
    if (std::isfinite(last)) largest = std::max(largest, std::abs(f - last));
    last = f;
  }
  return {n ? sum / n : NAN, largest};
}

} // namespace

void write_multirate(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log) {
  if (log) *log << "[multirate] the slab press on " << kMultirateNodes << " nodes: lockstep at 1 kHz, then real time\n";
  Scene scene = read_scene(scenes_dir / "haptic_slab_press.toml");
  const std::filesystem::path mesh = out / "multirate_slab.msh";
  const Mesh3 slab = [] {
#ifdef VTB_HAVE_CGAL_MESHERS
    return mesh_solid("slab", kMultirateNodes);
#else
    throw InputError("the multirate figure meshes a CGAL slab: this build has no CGAL meshers (VTB_WITH_CGAL=OFF)");
    return Mesh3{};
#endif
  }();
  write_msh(slab, mesh);
  scene.mesh.file = mesh;
  scene.solver.springs = "lloyd"; // the comparison is of the loops on one model: no fit to wait for
  scene.solver.step.filter = solvers::kFilterTensorMultigrid; // lag-free in both sessions
  scene.duration = 2.2;                                       // the press reaches 5 mm at 1 s, holds to 2 s, and lifts
  HapticsOptions ho;
  ho.lockstep = true;
  const HapticsReport lock = run_haptics(scene, ho);
  ho.lockstep = false;
  const HapticsReport rt = run_haptics(scene, ho);
  std::filesystem::remove(mesh);
  std::ostringstream trace, summary;
  trace << std::setprecision(6) << "t,lockstep,realtime\n";
  const std::size_t n = std::min(lock.t.size(), rt.t.size());
  const auto force = [](const HapticsReport& r, std::size_t k) {
    return std::hypot(r.probes[0].fx[k], r.probes[0].fy[k]);
  };
  for (std::size_t k = 0; k < n; ++k) trace << lock.t[k] << ',' << force(lock, k) << ',' << force(rt, k) << '\n';
  const auto [lock_held, lock_change] = held_force(lock);
  const auto [rt_held, rt_change] = held_force(rt);
  const auto nodes = slab.num_nodes();
  summary << std::setprecision(6)
          << "nodes,physics_dt_us,physics_time_ratio,physics_step_median_us,lockstep_step_median_us,held_lockstep,"
             "held_realtime,change_lockstep,change_realtime,tick_median_us,tick_p99_us,deadline_misses,fault_time,"
             "local_model_error_rms\n"
          << nodes << ',' << rt.physics_dt_us << ',' << rt.physics_time_ratio << ',' << rt.physics_step_median_us << ','
          << lock.physics_step_median_us << ',' << lock_held << ',' << rt_held << ',' << lock_change << ',' << rt_change
          << ',' << rt.tick_median_us << ',' << rt.tick_p99_us << ',' << rt.deadline_misses << ',' << rt.fault_time
          << ',' << rt.local_model_error_rms << '\n';
  write_files_atomically(out, {{"multirate_trace.csv", trace.str()}, {"multirate_summary.csv", summary.str()}});
}

} // namespace vtb::reproduction::parts
