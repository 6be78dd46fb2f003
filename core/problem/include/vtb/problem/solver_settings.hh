#pragma once
/// \file
/// A scene's [solver] settings by who takes them: the spring steppers, CVODE, the FEM. The scene
/// reader fills them once (SolverDesc in scene.hh); the integrators and the FEM take them as
/// they are. Their defaults are written here (the rest of [solver]'s in SolverDesc).

#include "vtb/problem/solver_names.hh"

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace vtb {

/// `[solver] kinematics`: the FEM's law, linear or geometrically exact (total Lagrangian, Newton
/// per step) with St. Venant-Kirchhoff's ("nonlinear") or the compressible neo-Hookean elastic
/// law ("neo-hookean"), each with the Kelvin-Voigt rate term (docs/fem.md).
enum class Kinematics { linear, svk, neo_hookean };
/// The names of the laws in `[solver] kinematics` and `--kinematics`, in the enum's order.
inline constexpr std::array<std::string_view, 3> kKinematics{"linear", "nonlinear", "neo-hookean"};
inline const char* kinematics_name(Kinematics k) {
  return kKinematics[static_cast<std::size_t>(k)].data();
}
/// The law a name of kKinematics names; nullopt for any other text.
inline std::optional<Kinematics> kinematics_named(std::string_view name) {
  for (std::size_t i = 0; i < kKinematics.size(); ++i)
    if (kKinematics[i] == name) return static_cast<Kinematics>(i);
  return std::nullopt;
}

/// The spring steppers' settings (explicit, filtered, implicit-euler): the integrators take
/// them as they are (IntegratorOptions is one).
struct SpringStepSettings {
  /// auto (default: full, or multigrid on large 3D meshes) | full | neighbors (the paper,
  /// conditionally stable) | tensor | multigrid
  std::string filter = solvers::kFilterAuto;
  bool momentum_correction = true;
  double strain_limit = 0.0;          ///< 0 = off (the default: it changes the physics)
  double step_budget = 0.0;           ///< s per step; 0 = none (filter_pick.hh)
  std::string linear_solver = "auto"; ///< implicit-euler: auto (direct in 2D, cg in 3D) | direct | cg
  double cg_tolerance = 1e-8;         ///< implicit-euler with cg: |r| <= tol |b|
};

/// CVODE's settings (cvode_solver.hh's CvodeOptions is one).
struct CvodeSettings {
  double rtol = 1e-8, atol = 1e-12;
};

/// The FEM's settings (reference_fem's FemOptions is one).
struct FemSettings {
  int degree = 1;      ///< FE_SimplexP degree: 1 or 2
  int refinements = 0; ///< uniform refinements of the scene's mesh
  /// generalized-alpha (rho_inf = 0, order 2, annihilates the highest modes) | newmark (average
  /// acceleration, order 2, no damping) | backward-euler (order 1)
  std::string scheme = "generalized-alpha";
  bool static_solve = false; ///< `static = true`: solve K u = f(t_end) once instead of stepping
  /// With static_solve: the equilibrium at every sample time instead (the loads' and drives'
  /// ramps as a load path), each continued from the last: a force-depth curve in one run.
  bool static_path = false;
  Kinematics kinematics = Kinematics::linear; ///< a geometrically exact law runs with backward Euler or static
  bool nonlinear() const { return kinematics != Kinematics::linear; }
};

} // namespace vtb
