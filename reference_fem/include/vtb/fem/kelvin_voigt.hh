#pragma once
/// \file
/// The continuum reference: a linear Kelvin-Voigt solid, sigma = C : (eps + tau d eps / dt),
/// plus mass damping, discretised with deal.II simplex finite elements on the very mesh the
/// spring model uses. The public interface carries no deal.II type.

#include "vtb/problem/output.hh"
#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"

#include <filesystem>
#include <functional>

#include <memory>

namespace vtb::fem {

using Kinematics = vtb::Kinematics;

/// The FEM's options: the scene's [solver] FEM settings as they are, the step, and what a
/// caller asks of a run.
struct FemOptions : FemSettings {
  double dt = 1e-3;
  std::filesystem::path frames_dir; ///< if set: frames/frame_NNNN.vtu per sample (deal.II DataOut)
  /// If set: called after every step with the share of the duration done (0-1], so that a long
  /// reference can show its progress.
  std::function<void(double)> progress;
  /// The systems' solver: auto (iterative_by_default) | direct | cg (CG preconditioned by Trilinos
  /// ML's AMG with the rigid-body modes; `cg-multigrid` is the same): the scene's
  /// `[solver] linear_solver`, the key implicit Euler reads too.
  std::string linear_solver = "auto";
  /// The AMG's near-null space with the rotations (default) or the translations alone: only
  /// tests turn them off, to show what the rotations are for.
  bool amg_rotations = true;
  /// The static load continuation's secant predictor (KelvinVoigtProblem::step_nonlinear): only
  /// tests turn it off, to show that it changes Newton's work and not the answer.
  bool secant_predictor = true;
  /// Newton's line search (KelvinVoigtProblem::line_search): only tests turn it off, to show
  /// what it changes.
  bool line_search = true;
  /// Nested iteration (docs/fem.md): a static nonlinear P2 solve refined r >= 1 times first
  /// solves at r - 1 and starts Newton at the whole load from that answer; summary.json says how
  /// far the probes moved between the two levels. Only tests turn it off.
  bool nested = true;
  /// Whether these options solve nested (the rule above).
  bool nests() const {
    return nested && static_solve && !static_path && nonlinear() && degree == 2 && refinements >= 1;
  }
};

/// `linear_solver = "auto"`: whether a system of this many dofs goes to AMG-preconditioned CG
/// rather than a direct factorisation (the crossover measured in docs/fem.md); `tangent`: Newton's
/// tangent, refactorised at every iteration, where the iterative solve wins far earlier in 3D.
bool iterative_by_default(int dim, long dofs, int ranks, bool tangent = false);
inline constexpr long kIterativeFromDofs2D = 2000000;
inline constexpr long kIterativeFromDofs3D = 110000;
inline constexpr long kIterativeFromDofs3DDistributed = 5000;
inline constexpr long kIterativeTangentFromDofs3D = 4000;

FemOptions options_from(const SolverDesc& solver);
/// Throws InputError unless the degree is 1 or 2, dt > 0, and nonlinear kinematics come with
/// backward Euler or the static solve.
void check_options(const FemOptions& options);

/// Simulates the scene's problem with the FEM and records, at every sample time, the probe
/// displacements, the support reactions (from the residual: the force each support exerts
/// on the body) and, if asked, the displacement at every node of the scene's mesh (for
/// node-by-node comparison with the spring model; the original nodes stay nodes under
/// refinement and for P2). RunReport.extra holds cells, dofs and the phase times.
template <int dim>
RunReport simulate(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                   Trajectory<dim>& out, bool record_field = false);

/// The same solver (one code path, another linear-algebra backend) distributed over the MPI
/// ranks of mpirun (parallel::fullydistributed triangulation, Trilinos matrices, a Trilinos
/// direct solver); every rank returns the same trajectory. Requires an MpiScope alive.
template <int dim>
RunReport simulate_distributed(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                               Trajectory<dim>& out, bool record_field = false);

/// Initialises and finalises MPI when the process was started by mpirun (OMPI_COMM_WORLD_SIZE
/// or PMI_SIZE set); otherwise does nothing. One per process, in main.
class MpiScope {
public:
  MpiScope(int& argc, char**& argv);
  ~MpiScope();
  MpiScope(const MpiScope&) = delete;
  MpiScope& operator=(const MpiScope&) = delete;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};
int mpi_size(); ///< 1 without MPI
int mpi_rank(); ///< 0 without MPI

/// `vtb run SCENE --solver fem`: same files as the spring solvers (distributed when run under
/// mpirun with more than one rank; rank 0 writes).
/// An empty `out_dir` writes nothing; `tables`, when set, receives what the files hold.
RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames = false,
                    RunTables* tables = nullptr);

} // namespace vtb::fem
