#include "vtb/problem/overrides.hh"

#include "vtb/base/input_error.hh"
#include "vtb/problem/solver_registry.hh"

#include <cmath>

namespace vtb {

double checked_dt(double dt, const char* name) {
  if (!(dt > 0) || !std::isfinite(dt)) throw InputError(std::string(name) + " must be a positive number");
  return dt;
}

void SolverOverrides::apply(std::string& kind_out, std::string& filter_out, double& dt_out,
                            std::string& springs_out) const {
  if (solver) solvers::select(*solver, "--solver", kind_out, filter_out);
  if (filter) filter_out = *filter;
  if (dt) dt_out = checked_dt(*dt);
  if (springs) springs_out = *springs;
}

} // namespace vtb
