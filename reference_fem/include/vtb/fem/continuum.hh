#pragma once
/// \file
/// The continuum's static answer, the yardstick every spring-versus-FEM number is measured
/// against (docs/fidelity.md): the linear static displacement at the scene's nodes from P2 on
/// the scene's mesh refined until a refinement moves the answer by less than
/// ContinuumOptions::tolerance, within a budget of dofs decided before each solve.

#include "vtb/problem/problem.hh"

#include <Eigen/Core>

#include <optional>
#include <string>

namespace vtb::fem {

struct ContinuumOptions {
  /// Converged when one more uniform refinement moves the nodal answer by less than this
  /// (relative L2 over the scene's nodes).
  double tolerance = 0.01;
  /// No level whose estimated dofs exceed this is solved (a direct solve: UMFPACK on P2 took
  /// 10 s and 1.1 GB at 54k dofs in 3D, 0.3 s at 70k in 2D). 0: kContinuumDofs of the dimension.
  long max_dofs = 0;
  int max_refinements = 4;
  /// Drives at their full prescribed displacement instead of held at zero: the final state of a
  /// scene driven by displacements (a transient reference's level, `vtb study`), where the load
  /// check holds them like fixes.
  bool drives_displaced = false;
};

/// The default budget of dofs per dimension (ContinuumOptions::max_dofs).
inline constexpr long kContinuumDofs2D = 600000;
inline constexpr long kContinuumDofs3D = 60000;
/// A spring fit's training answers (cached per mesh, so paid once) solve P2 on the mesh itself
/// up to this many dofs in 3D even past kContinuumDofs3D, the budget for its refinements: bodies
/// of up to about 5,000 nodes train on the continuum (a factor of about 2 GB at 100,000 dofs).
/// Below it a graded mesh and a uniform one of the same body train on the same answers
/// (docs/meshes.md); the per-run load check keeps kContinuumDofs3D.
inline constexpr long kContinuumFitDofs3D = 110000;

/// What the ladder of refinements found.
template <int dim> struct ContinuumAnswer {
  Nodal<dim> u;           ///< static displacement at the scene's nodes (the finest level solved)
  int refinements = 0;    ///< of the finest level solved
  long dofs = 0;          ///< of the finest level solved
  double change = -1;     ///< relative change of the last refinement; < 0: only one level solved
  bool converged = false; ///< change < tolerance
  /// The coarsest level within the tolerance of the finest (converged: the level before the
  /// last, whose answer the last refinement moved by `change`; else the finest): the level a
  /// transient continuum reference runs at (`vtb compare --reference fem`).
  int sufficient_refinements = 0;
  double seconds = 0; ///< all levels
  /// One line: "P2 refined 1x (53,907 dofs), converged: the last refinement moved it 0.16 %", or
  /// why convergence was not checked (the next level's dofs above the budget).
  std::string how;
};

/// The continuum's static answers to many loads at once (a spring fit's training set).
struct ContinuumAnswers {
  Eigen::MatrixXd u; ///< (node v, component i) -> row dim v + i; one column per load
  int refinements = 0;
  double change = -1; ///< of the last refinement (Frobenius, relative); < 0: one level solved
  bool converged = false;
  std::string how; ///< as ContinuumAnswer::how
};

/// The continuum's static answers to nodal loads F (rows as ContinuumAnswers::u; the rows of
/// held nodes are ignored), read as P1 body forces g = M1^-1 F (M1 the P1 consistent mass of
/// the scene's mesh at unit density: then P1 on the mesh answers exactly K1^-1 F, and the
/// continuum the same distributed load), the scene's fixes and drives held at zero, by the
/// ladder of continuum_static on all the answers at once. nullopt when not even P2 on the mesh
/// fits the budget.
template <int dim>
std::optional<ContinuumAnswers> continuum_answers(const Problem<dim>& problem, const MaterialDesc& material,
                                                  const Eigen::MatrixXd& F, const ContinuumOptions& options = {});

/// P2's dofs on the mesh (the ladder's first level), counted before any solve.
template <int dim> long continuum_first_dofs(const Mesh<dim>& mesh);
/// The budget of dofs in this dimension (ContinuumOptions::max_dofs, or the default).
long continuum_budget(int dim, const ContinuumOptions& options = {});

/// The problem as a static test: every load at its full value (no ramp), drives held at zero
/// like fixes (or, `drives_displaced`, at their full displacement); the solve of
/// `continuum_static` and of the springs' load check (load_check.hh).
template <int dim> Problem<dim> static_problem(const Problem<dim>& problem, bool drives_displaced = false);

/// Solves static_problem(problem) with P2 at refinements 0, 1, ... until converged, the budget
/// or max_refinements stops it. nullopt when not even P2 on the mesh fits the budget.
template <int dim>
std::optional<ContinuumAnswer<dim>> continuum_static(const Problem<dim>& problem, const MaterialDesc& material,
                                                     const ContinuumOptions& options = {});

} // namespace vtb::fem
