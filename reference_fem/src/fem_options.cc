// The FEM's options from a scene and their check: in the FEM's base library, which loads no
// deal.II (the CLI checks a scene's options before the plugin is loaded; plugin/client.cc).
#include "vtb/base/input_error.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/problem/overrides.hh"

namespace vtb::fem {

FemOptions options_from(const SolverDesc& solver) {
  FemOptions o;
  static_cast<FemSettings&>(o) = solver.fem;
  o.dt = solver.dt;
  o.linear_solver = solver.step.linear_solver; // one key, read once by the scene (scene.cc)
  return o;
}

void check_options(const FemOptions& options) {
  if (options.degree < 1 || options.degree > 2) throw InputError("[solver].degree must be 1 or 2");
  checked_dt(options.dt, "[solver].dt");
  if (options.nonlinear() && !options.static_solve && options.scheme != "backward-euler")
    throw InputError(std::string("[solver].kinematics = \"") + kinematics_name(options.kinematics) +
                     "\" runs with scheme = \"backward-euler\" or static = true, not "
                     "scheme = \"" +
                     options.scheme + "\"");
  const auto& k = options.linear_solver;
  if (k != "auto" && k != "direct" && k != "cg" && k != "cg-multigrid")
    throw InputError("[solver].linear_solver = \"" + k + "\" is not auto, direct, cg or cg-multigrid");
}

bool iterative_by_default(int dim, long dofs, int ranks, bool tangent) {
  // docs/fem.md, "Linear solvers": serially the factorisation wins wherever it fits (one solve
  // at 56k dofs: 4.1 s against CG's 6.4 s; a transient's or a fit's many right-hand sides
  // favour it further) and stops at the fit's budget (kContinuumFitDofs3D, a factor of about
  // 2 GB); under MPI Amesos gathers the matrix on one rank. In 2D the fill stays small.
  if (dim == 2) return dofs > kIterativeFromDofs2D;
  // Newton's tangent, refactorised at every iteration, against AMG-preconditioned CG with
  // inexact corrections: on a graded neo-Hookean disc press (P2, static) 3.0 s against 2.2 s
  // at 4,500 dofs and 16.0 s against 9.3 s at 13,077 (docs/fem.md).
  if (tangent) return dofs > kIterativeTangentFromDofs3D;
  return dofs > (ranks > 1 ? kIterativeFromDofs3DDistributed : kIterativeFromDofs3D);
}

} // namespace vtb::fem
