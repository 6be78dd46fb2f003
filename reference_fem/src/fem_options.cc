// The FEM's options from a scene and their check: in the FEM's base library, which loads no
// deal.II (the CLI checks a scene's options before the plugin is loaded; plugin/client.cc).
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/meshes/input_error.hh"

namespace vtb::fem {

FemOptions options_from(const SolverDesc& s) {
  FemOptions o;
  o.degree = s.degree;
  o.refinements = s.refinements;
  o.scheme = s.scheme;
  o.static_solve = s.static_solve;
  o.static_path = s.static_path;
  o.dt = s.dt;
  o.kinematics = s.kinematics == "nonlinear"     ? Kinematics::svk
                 : s.kinematics == "neo-hookean" ? Kinematics::neo_hookean
                                                 : Kinematics::linear;
  return o;
}

void check_options(const FemOptions& options) {
  if (options.degree < 1 || options.degree > 2) throw InputError("[solver].degree must be 1 or 2");
  if (!(options.dt > 0)) throw InputError("[solver].dt must be > 0");
  if (options.nonlinear() && !options.static_solve && options.scheme != "backward-euler")
    throw InputError(std::string("[solver].kinematics = \"") +
                     (options.kinematics == Kinematics::svk ? "nonlinear" : "neo-hookean") +
                     "\" runs with scheme = \"backward-euler\" or static = true, not "
                     "scheme = \"" +
                     options.scheme + "\"");
}

} // namespace vtb::fem
