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
}

} // namespace vtb::fem
