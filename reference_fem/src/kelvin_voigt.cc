// The entry points of the one Kelvin-Voigt solver of kelvin_voigt_problem.hh: serially on
// deal.II's triangulation and sparse matrices (backends.hh), and distributed over MPI ranks
// (mpirun -np N) on a parallel::fullydistributed::Triangulation with Trilinos matrices, vectors
// and solvers, where every rank ends with the same trajectory. Also the MPI scope of the process.
#include "kelvin_voigt_problem.hh"

#include <deal.II/base/multithread_info.h>

#include <cstdlib>

namespace vtb::fem {

template <int dim>
RunReport simulate(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                   Trajectory<dim>& out, bool record_field) {
  check_options(options);
  // One thread: deal.II's threaded vector reductions sum in an order that depends on the thread
  // count, which moved the reference's last digits between machines and under mpirun (where
  // deal.II runs one thread). Measured on the 517-node plate's P2 reference: 11.5 s on one
  // thread, 11.6 s on two; the direct solve, single-threaded either way, is the cost.
  dealii::MultithreadInfo::set_thread_limit(1);
  KelvinVoigtProblem<dim, SerialBackend<dim>> problem(model, material, options, MPI_COMM_SELF);
  return problem.run(out, record_field);
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
  KelvinVoigtProblem<dim, DistributedBackend<dim>> problem(model, material, options, MPI_COMM_WORLD);
  return problem.run(out, record_field);
}

template RunReport simulate_distributed<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&,
                                           bool);
template RunReport simulate_distributed<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&,
                                           bool);

} // namespace vtb::fem
