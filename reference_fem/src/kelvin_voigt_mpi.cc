// The Kelvin-Voigt reference distributed over MPI ranks (mpirun -np N): the one solver of
// kelvin_voigt_problem.hh on a parallel::fullydistributed::Triangulation with Trilinos
// matrices, vectors and direct solver (backends.hh). Every rank ends with the same trajectory.
// Also the MPI scope of the process.
#include "kelvin_voigt_problem.hh"

#include <cstdlib>

namespace vtb::fem {

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
