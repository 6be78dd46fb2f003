#pragma once
/// \file
/// Every solver of the testbed behind one call, for the harness: the spring integrators,
/// CVODE and the deal.II reference, each recording the full nodal field at sample times; and
/// `vtb run` as a call (the CLI and the Python module both go through `run`, so their numbers
/// are one run's).

#include "vtb/fem/continuum.hh"
#include "vtb/problem/output.hh"
#include "vtb/problem/scene.hh"
#include "vtb/solvers/simulation.hh"
#include "vtb/springs/load_check.hh"

#include <filesystem>
#include <optional>
#include <string>

namespace vtb::harness {

/// Runs `solver` on the model (its dt from the scene unless `dt` > 0; explicit defaults to
/// half its predicted stability limit when the scene's dt is above it).
template <int dim>
RunReport run_solver(const Scene& scene, const Model<dim>& model, const std::string& solver, double dt,
                     Trajectory<dim>& out);

/// The static ladders a yardstick solved for the springs' load check, kept for a reference that
/// needs the same solve again (`vtb compare --reference fem`'s level always; `vtb study`'s where
/// the scene drives nothing, so that holding the drives or displacing them is the same problem).
/// What they were solved for is kept with them.
struct KeptLadders {
  std::optional<fem::ContinuumAnswer<2>> plane;
  std::optional<fem::ContinuumAnswer<3>> solid;
  int nodes = -1;
  double young_modulus = 0, poisson_ratio = 0, thickness = 0;
  template <int dim> std::optional<fem::ContinuumAnswer<dim>>& get() {
    if constexpr (dim == 2)
      return plane;
    else
      return solid;
  }
};

/// The continuum as the springs' yardstick (load_check.hh): reference_fem's continuum_static,
/// P2 refined until converged within its budget of dofs (vtb/fem/continuum.hh). With `keep`, its
/// answers are kept there too.
Yardstick continuum_yardstick(KeptLadders* keep = nullptr);

/// fem::continuum_static(problem, material, options), or `kept`'s answer where it is that solve:
/// the same problem and material, the default options, and drives held or none to displace
/// (`reused`, where given, says which).
template <int dim>
std::optional<fem::ContinuumAnswer<dim>> static_ladder(const Problem<dim>& problem, const MaterialDesc& material,
                                                       const fem::ContinuumOptions& options, KeptLadders* kept,
                                                       bool* reused = nullptr);

/// Options of `vtb run` that override the scene.
struct RunOverrides {
  std::optional<std::string> solver; ///< any registry name: a kind, or a kind with its filter
  std::optional<double> dt;
  std::optional<double> duration;
  /// The FEM's law: linear | nonlinear | neo-hookean (a geometrically exact one steps with
  /// backward Euler when the scene names a scheme it does not take).
  std::optional<std::string> kinematics;
};

/// The scene with the overrides applied; InputError for an unknown solver, a non-positive or
/// non-finite --dt/--duration, an unknown --kinematics, or a step longer than the run.
Scene with_overrides(const Scene& scene, const RunOverrides& overrides);

/// Runs the scene with the solver of its [solver].kind. With `out_dir` set, writes probes.csv,
/// reactions.csv and summary.json there (all or nothing; `frames`: the VTU frames too); an
/// empty `out_dir` writes nothing. Returns the tables those files hold.
RunTables run(const Scene& scene, const std::filesystem::path& out_dir, bool frames = false,
              const FitProgress& progress = {});

} // namespace vtb::harness
