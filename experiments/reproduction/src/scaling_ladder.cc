// scaling.csv: the spring solvers over mesh ladders (structured 2D rectangles and 3D boxes for
// the fitted exponents; CGAL Mesh_3 slabs of about 2k, 10k and 50k nodes, the meshes a user
// brings), each with its precompute, median step, heap and error against the FEM.
#include "reproduce_parts.hh"
#include "vtb/base/atomic_file.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/solvers/integrator.hh"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <malloc.h>
#include <ostream>
#include <sstream>

namespace vtb::reproduction::parts {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables
namespace {

/// Heap bytes in use (glibc), to measure what an integrator holds.
std::size_t heap_in_use() {
  return mallinfo2().uordblks;
}

/// The solvers of the ladder: the filter by its factor and by its V-cycle, the lag-free tensor
/// filter by its factor (2D, and 3D below kTensorCycleFreeNodes3D free nodes: its factor holds
/// dim^2 = 9x the scalar one's entries) and by its block V-cycle (3D), the implicit Euler
/// baseline (direct in 2D, CG in 3D), and Bullet as a peer.
constexpr const char* kLadderSolvers[] = {solvers::kFilteredFull,   solvers::kFilteredMultigrid,
                                          solvers::kFilteredTensor, solvers::kFilteredTensorMultigrid,
                                          solvers::kImplicitEuler,  solvers::kBullet};

/// Precompute, median step and heap of `solver` on `model`, timed over `steps` steps alone:
/// apart from the error run, whose sampling (the field, strains and rotations every other
/// step) leaves the caches cold for the next step (the 10k slab's full filter times 6.0 ms per
/// step inside the run against 3.1 ms here).
template <int dim>
void time_solver(const Scene& scene, const Model<dim>& model, const char* solver, int steps, double& pre,
                 double& median, double& bytes) {
  IntegratorOptions io = integrator_options(scene.solver);
  solvers::select(solver, "scaling", io.kind, io.filter);
  const std::size_t before = heap_in_use();
  const auto a = std::chrono::steady_clock::now();
  auto integ = make_integrator(model, io);
  pre = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
  bytes = static_cast<double>(heap_in_use() - before);
  State<dim> s = initial_state(model);
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    const auto b = std::chrono::steady_clock::now();
    integ->step(s);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - b).count());
  }
  median = step_stats(std::move(times)).median;
}

template <int dim> std::string scaling_rows(const Scene& scene, const char* family) {
  std::ostringstream os;
  with_model(scene, [&](const auto& model) {
    if constexpr (std::decay_t<decltype(model)>::dimension == dim) {
      const int steps = static_cast<int>(std::lround(scene.duration / scene.solver.dt));
      // The reference: deal.II's Kelvin-Voigt P1 on the same mesh, same dt (what compare's
      // default reference is); the error is the largest relative L2 displacement error over
      // the samples, springs' modelling error included.
      Trajectory<dim> ref;
      run_solver(scene, model, solvers::kFem, 0, ref);
      for (const char* solver : kLadderSolvers) {
        // The tensor filter by its factor in 2D and on the small 3D meshes where auto runs it
        // (its factor's 9 values per node pair grow past the cycle's cost above), by its block
        // V-cycle in 3D.
        if (dim == 3 && solver == std::string(solvers::kFilteredTensor) &&
            model.free_nodes.size() >= kTensorCycleFreeNodes3D)
          continue;
        if (dim == 2 && solver == std::string(solvers::kFilteredTensorMultigrid)) continue;
        double pre = 0, median = 0, bytes = std::nan("");
        Trajectory<dim> tr;
        const RunReport r = run_solver(scene, model, solver, 0, tr);
        if (solver == std::string(solvers::kBullet)) { // its own loop: timed within the run (so colder than the
                                                       // others); heap not measured
          pre = r.precompute_seconds + r.calibration_seconds;
          median = r.step_seconds.median;
        } else {
          time_solver(scene, model, solver, steps, pre, median, bytes);
        }
        const double error = r.stable ? compare(tr, ref).displacement_max : std::nan("");
        // auto_pick: this row is what a scene with no filter key runs on this mesh (filter = auto).
        const bool picked = solver == "filtered-" + chosen_filter(model, solvers::kFilterAuto);
        os << family << ',' << dim << ',' << model.num_nodes() << ',' << model.net.num_springs() << ',' << solver << ','
           << std::setprecision(6) << pre * 1e3 << ',' << median * 1e6 << ',' << bytes / 1.0e6 << ',' << error << ','
           << (picked ? "true" : "false") << '\n';
      }
    }
  });
  return os.str();
}

/// A clamped bar under a step load at its free end, dt = 0.01 s, heavily damped (tau = 2 s):
/// `mesh` is the [mesh] table's generate line. Lloyd's springs: a speed ladder, and the
/// calibration does not change a step's cost (same springs, other constants); the fit's
/// accuracy is fidelity.csv's.
std::string scaling_scene(int dim, const std::string& mesh, int steps) {
  std::ostringstream os;
  os << "[scene]\nname = \"scaling\"\nduration = " << 0.01 * steps << "\noutput_interval = " << 0.001 * steps
     << "\n[mesh]\ngenerate = " << mesh
     << "\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " << (dim == 2 ? "0.3333" : "0.25")
     << "\ndensity = 1000.0\n"
     << (dim == 2 ? "thickness = 0.001\n" : "") << "retardation_time = 2.0\n"
     << "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = "
     << (dim == 2 ? "[0.1, 0.0]" : "[0.1, 0.0, 0.0]")
     << "\n[solver]\nkind = \"filtered\"\ndt = 0.01\nsprings = \"lloyd\"\n";
  return os.str();
}

std::string structured(int dim, int n) {
  std::ostringstream os;
  if (dim == 2)
    os << "{ shape = \"rectangle\", size = [0.2, 0.05], divisions = [" << 4 * n << ", " << n << "] }";
  else
    os << "{ shape = \"box\", size = [0.2, 0.05, 0.05], divisions = [" << 4 * n << ", " << n << ", " << n << "] }";
  return os.str();
}

} // namespace

void write_scaling(const std::filesystem::path& out, bool quick, std::ostream* log) {
  std::ostringstream os;
  os << "family,dim,nodes,springs,solver,precompute_ms,step_median_us,heap_mb,error_vs_fem,auto_pick\n";
  const std::vector<int> ladder2 = quick ? std::vector<int>{4, 8, 16, 32} : std::vector<int>{4, 8, 16, 32, 64};
  const std::vector<int> ladder3 = quick ? std::vector<int>{2, 3, 4, 6} : std::vector<int>{2, 3, 4, 6, 8, 12};
  const std::vector<int> slabs = quick ? std::vector<int>{2000, 10000} : std::vector<int>{2000, 10000, 50000};
  const int steps = quick ? 20 : 50;
  for (int n : ladder2) {
    if (log) *log << "[scaling] rectangle " << 4 * n << " x " << n << "\n";
    os << scaling_rows<2>(parse_scene(scaling_scene(2, structured(2, n), steps), "scaling-2d", "."), "rectangle");
  }
  for (int n : ladder3) {
    if (log) *log << "[scaling] box " << 4 * n << " x " << n << " x " << n << "\n";
    os << scaling_rows<3>(parse_scene(scaling_scene(3, structured(3, n), steps), "scaling-3d", "."), "box");
  }
  for (int n : slabs) {
    if (log) *log << "[scaling] CGAL slab of about " << n << " nodes\n";
    const std::string mesh =
        "{ shape = \"box\", size = [0.2, 0.05, 0.05], mesher = \"cgal\", nodes = " + std::to_string(n) + " }";
    try {
      os << scaling_rows<3>(parse_scene(scaling_scene(3, mesh, steps), "scaling-slab", "."), "cgal-slab");
    } catch (const InputError& e) { // a build without CGAL's meshers
      if (log) *log << "[scaling] skipped: " << e.what() << "\n";
    }
  }
  write_files_atomically(out, {{"scaling.csv", os.str()}});
}

} // namespace vtb::reproduction::parts
