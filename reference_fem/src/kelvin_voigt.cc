// The entry points of the one Kelvin-Voigt solver of kelvin_voigt_problem.hh: serially on
// deal.II's triangulation and sparse matrices (backends.hh), and distributed over MPI ranks
// (mpirun -np N) on a parallel::fullydistributed::Triangulation with Trilinos matrices, vectors
// and solvers, where every rank ends with the same trajectory. Also the MPI scope of the process.
#include "kelvin_voigt_problem.hh"

#include <deal.II/base/multithread_info.h>

#include <cmath>
#include <cstdlib>
#include <optional>

namespace vtb::fem {
namespace {

/// The probes' largest displacement change between two levels' last samples, relative to the
/// finer level's displacement there; NaN without probes.
template <int dim> double probe_move(const Trajectory<dim>& coarse, const Trajectory<dim>& fine) {
  if (coarse.probe_u.empty() || fine.probe_u.empty() || fine.probe_u.back().empty()) return std::nan("");
  double move = 0;
  for (std::size_t p = 0; p < fine.probe_u.back().size(); ++p) {
    const auto& uf = fine.probe_u.back()[p];
    const double scale = uf.norm();
    if (scale > 0) move = std::max(move, (uf - coarse.probe_u.back()[p]).norm() / scale);
  }
  return move;
}

/// A run at options' refinements; nested (FemOptions::nests), first at one refinement fewer,
/// recursively. `answer`, if set, receives the displacement at the support points.
template <int dim, class Backend>
RunReport run_level(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                    Trajectory<dim>& out, bool record_field, MPI_Comm comm, std::optional<LevelAnswer<dim>>* answer) {
  std::optional<LevelAnswer<dim>> coarse;
  RunReport coarse_rep;
  Trajectory<dim> coarse_out;
  if (options.nests()) {
    FemOptions o = options;
    o.refinements -= 1;
    o.frames_dir.clear();
    o.progress = nullptr;
    coarse_rep = run_level<dim, Backend>(model, material, o, coarse_out, false, comm, &coarse);
    if (!coarse_rep.stable) coarse.reset(); // the fine level then starts from rest
  }
  KelvinVoigtProblem<dim, Backend> problem(model, material, options, comm);
  if (coarse) problem.start_from(&*coarse);
  RunReport rep = problem.run(out, record_field);
  if (answer) {
    // Points within a billionth of the body's size are one (LevelAnswer in grid.hh).
    const auto& x = model.mesh.points;
    const double size = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
    *answer = problem.answer(1e-9 * size, comm);
  }
  if (options.nests()) {
    const double coarse_seconds = coarse_rep.precompute_seconds + coarse_rep.total_seconds;
    rep.precompute_seconds += coarse_seconds; // the coarse level is part of this run's cost
    rep.extra.push_back({"nested_coarse_seconds", coarse_seconds});
    for (const auto& [key, value] : coarse_rep.extra)
      if (key == "dofs" || key == "newton_iterations") rep.extra.push_back({"nested_coarse_" + key, value});
    if (coarse) rep.extra.push_back({"nested_probe_move", probe_move(coarse_out, out)});
  }
  return rep;
}

} // namespace

template <int dim>
RunReport simulate(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                   Trajectory<dim>& out, bool record_field) {
  check_options(options);
  // One thread: deal.II's threaded vector reductions sum in an order that depends on the thread
  // count, which moved the reference's last digits between machines and under mpirun (where
  // deal.II runs one thread). Measured on the 517-node plate's P2 reference: 11.5 s on one
  // thread, 11.6 s on two; the direct solve, single-threaded either way, is the cost.
  dealii::MultithreadInfo::set_thread_limit(1);
  return run_level<dim, SerialBackend<dim>>(model, material, options, out, record_field, MPI_COMM_SELF, nullptr);
}

template RunReport simulate<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&, bool);
template RunReport simulate<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&, bool);

struct MpiScope::Impl {
  std::unique_ptr<dealii::Utilities::MPI::MPI_InitFinalize> init;
};

MpiScope::MpiScope(int& argc, char**& argv) : m_impl(std::make_unique<Impl>()) {
  // Only under a launcher: a plain run never touches MPI.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE"))
    m_impl->init = std::make_unique<dealii::Utilities::MPI::MPI_InitFinalize>(argc, argv, 1);
}
MpiScope::~MpiScope() = default;

int mpi_size() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  return initialized ? static_cast<int>(dealii::Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) : 1;
}
int mpi_rank() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  return initialized ? static_cast<int>(dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD)) : 0;
}

template <int dim>
RunReport simulate_distributed(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                               Trajectory<dim>& out, bool record_field) {
  check_options(options);
  return run_level<dim, DistributedBackend<dim>>(model, material, options, out, record_field, MPI_COMM_WORLD, nullptr);
}

template RunReport simulate_distributed<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&,
                                           bool);
template RunReport simulate_distributed<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&,
                                           bool);

} // namespace vtb::fem
