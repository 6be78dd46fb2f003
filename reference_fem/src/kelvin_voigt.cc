// The serial Kelvin-Voigt reference: the one solver of kelvin_voigt_problem.hh on deal.II's
// serial triangulation, sparse matrices and UMFPACK (backends.hh).
#include "kelvin_voigt_problem.hh"

#include <deal.II/base/multithread_info.h>

namespace vtb::fem {

FemOptions options_from(const SolverDesc& s) {
  FemOptions o;
  o.degree = s.degree;
  o.refinements = s.refinements;
  o.scheme = s.scheme;
  o.static_solve = s.static_solve;
  o.dt = s.dt;
  o.nonlinear = s.kinematics == "nonlinear";
  return o;
}

void check_options(const FemOptions& options) {
  if (options.degree < 1 || options.degree > 2) throw InputError("[solver].degree must be 1 or 2");
  if (!(options.dt > 0)) throw InputError("[solver].dt must be > 0");
  if (options.nonlinear && !options.static_solve && options.scheme != "backward-euler")
    throw InputError("[solver].kinematics = \"nonlinear\" runs with scheme = \"backward-euler\" or static = true, not "
                     "scheme = \"" +
                     options.scheme + "\"");
}

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
