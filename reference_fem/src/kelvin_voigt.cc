// The serial Kelvin-Voigt reference: the one solver of kelvin_voigt_problem.hh on deal.II's
// serial triangulation, sparse matrices and UMFPACK (backends.hh).
#include "kelvin_voigt_problem.hh"

#include <deal.II/base/multithread_info.h>

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

} // namespace vtb::fem
