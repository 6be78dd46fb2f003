#include "overrides.hh"
#include "commands.hh"

#include "vtb/base/input_error.hh"
#include "vtb/problem/solver_registry.hh"

#include <algorithm>
#include <cmath>

namespace vtb::cli {

HapticsOptions::Fault parse_fault(const std::string& spec, double& time) {
  const auto at = spec.find('@');
  const std::string kind = spec.substr(0, at);
  if (at == std::string::npos || (kind != "stall" && kind != "nan"))
    throw InputError("--fault \"" + spec + "\": expected stall@T or nan@T (T in seconds)");
  try {
    std::size_t used = 0;
    time = std::stod(spec.substr(at + 1), &used);
    if (used != spec.size() - at - 1 || !(time >= 0) || !std::isfinite(time)) throw std::invalid_argument("");
  } catch (const std::exception&) {
    throw InputError("--fault \"" + spec + "\": T must be a time >= 0 in seconds");
  }
  return kind == "stall" ? HapticsOptions::Fault::stall : HapticsOptions::Fault::nan;
}

void add_kinematics_option(CLI::App* cmd, std::string& into) {
  cmd->add_option("--kinematics", into,
                  "The FEM's law, overriding [solver].kinematics: linear, nonlinear (St. Venant-Kirchhoff) or "
                  "neo-hookean (the reference for deep presses; docs/fem.md)");
}

} // namespace vtb::cli
