// The parts of continuum.hh that need no finite element: the ladder's size and budget, and the
// static problem it solves. In the FEM's base library, so that a run asks them without loading
// deal.II (plugin/client.cc).
#include "continuum_counts.hh"
#include "vtb/fem/continuum.hh"

namespace vtb::fem {

template <int dim> long continuum_first_dofs(const Mesh<dim>& mesh) {
  return static_cast<long>(counts(mesh).p2_dofs(dim));
}

long continuum_budget(int dim, const ContinuumOptions& options) {
  return options.max_dofs > 0 ? options.max_dofs : (dim == 2 ? kContinuumDofs2D : kContinuumDofs3D);
}

template <int dim> Problem<dim> static_problem(const Problem<dim>& problem, bool drives_displaced) {
  Problem<dim> p = problem;
  for (auto& load : p.loads) load.start = load.ramp = 0;
  for (auto& s : p.supports)
    if (drives_displaced) {
      s.start = s.ramp = 0;
    } else {
      s.driven = false;
      s.displacement.setZero();
    }
  p.duration = p.output_interval = 1.0;
  return p;
}

template long continuum_first_dofs<2>(const Mesh<2>&);
template long continuum_first_dofs<3>(const Mesh<3>&);
template Problem<2> static_problem<2>(const Problem<2>&, bool);
template Problem<3> static_problem<3>(const Problem<3>&, bool);

} // namespace vtb::fem
