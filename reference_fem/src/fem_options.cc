// The FEM's options from a scene and their check: in the FEM's base library, which loads no
// deal.II (the CLI checks a scene's options before the plugin is loaded; plugin/client.cc).
#include "vtb/base/input_error.hh"
#include "vtb/fem/kelvin_voigt.hh"

namespace vtb::fem {

FemOptions options_from(const SolverDesc& s) {
  FemOptions o;
  o.degree = s.degree;
  o.refinements = s.refinements;
  o.scheme = s.scheme;
  o.static_solve = s.static_solve;
  o.static_path = s.static_path;
  o.dt = s.dt;
  for (const Kinematics k : {Kinematics::linear, Kinematics::svk, Kinematics::neo_hookean})
    if (s.kinematics == kinematics_name(k)) o.kinematics = k;
  return o;
}

const char* kinematics_name(Kinematics kinematics) {
  switch (kinematics) {
  case Kinematics::svk:
    return "nonlinear";
  case Kinematics::neo_hookean:
    return "neo-hookean";
  case Kinematics::linear:
    break;
  }
  return "linear";
}

void check_options(const FemOptions& options) {
  if (options.degree < 1 || options.degree > 2) throw InputError("[solver].degree must be 1 or 2");
  if (!(options.dt > 0)) throw InputError("[solver].dt must be > 0");
  if (options.nonlinear() && !options.static_solve && options.scheme != "backward-euler")
    throw InputError(std::string("[solver].kinematics = \"") + kinematics_name(options.kinematics) +
                     "\" runs with scheme = \"backward-euler\" or static = true, not "
                     "scheme = \"" +
                     options.scheme + "\"");
}

} // namespace vtb::fem
