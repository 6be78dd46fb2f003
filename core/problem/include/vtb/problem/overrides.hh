#pragma once
/// \file
/// What a user may change of a scene's [solver] from outside the scene file: `vtb run`'s and
/// `vtb view`'s --solver/--filter/--dt, the viewer's controls, Python's keyword arguments. One
/// function applies them and one checks a step, so that every channel accepts and refuses
/// alike (ctest Overrides.*, tests/python/test_simulation.py).

#include <optional>
#include <string>

namespace vtb {

/// The one rule for a step: a positive finite number of seconds. Returns dt; throws InputError
/// "<name> must be a positive number" otherwise. Every step from outside the scene file is
/// checked by it (name "--dt"), and so are the integrators' and the FEM's options.
double checked_dt(double dt, const char* name = "--dt");

struct SolverOverrides {
  std::optional<std::string> solver; ///< any registry name: a kind, or a kind with its filter (filtered-tensor)
  std::optional<std::string> filter; ///< wins over the filter a solver name implies
  std::optional<double> dt;
  std::optional<std::string> springs;

  /// Applies the overrides given to the fields of a scene's [solver] or of a stepper's controls:
  /// the solver through the registry (InputError for a name it does not know), then the filter,
  /// the step (checked_dt) and the springs.
  void apply(std::string& kind, std::string& filter, double& dt, std::string& springs) const;
};

} // namespace vtb
