#pragma once
/// \file
/// The spring solvers' common interface: precompute once (in the constructor), then `step`
/// advances the state by the fixed dt and allocates nothing.

#include "vtb/problem/solver_names.hh"
#include "vtb/problem/solver_settings.hh"
#include "vtb/springs/model.hh"

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace vtb {

/// Mutable simulation state: displacements u and velocities v of every node at time t.
template <int dim> struct State {
  double t = 0;
  Nodal<dim> u;
  Nodal<dim> v;
  /// Forces applied from outside the scene during the run (the haptic probe's contact),
  /// added to the scene's loads when sized like u; empty otherwise.
  Nodal<dim> applied;
  /// The stiffness (N/m, isotropic) of the couplings whose forces `applied` holds (a user's
  /// pull: k (target - x) at its node; a haptic contact: the virtual coupling's k shared by
  /// the touched facet's weights), per node; empty or zero where there is none. The tensor and
  /// full filters and implicit Euler solve them implicitly, as they do their springs (without
  /// it a pull 4x a spring's stiffness diverged at dt = 10 ms); the multigrid and neighbour
  /// filters apply the force alone.
  Eigen::VectorXd applied_stiffness;
  /// The damping (N s/m, isotropic) of the same couplings (a contact's -c (v - v_handle)),
  /// per node; empty or zero where there is none. Solved implicitly with the stiffness.
  Eigen::VectorXd applied_damping;
  /// Nodes that share one coupling (a tool tip's footprint: the coupling's force spread by
  /// weights w, sum 1): the same group id >= 0, their applied_stiffness and applied_damping
  /// w_i k and w_i b. Its Jacobian is k w w^T, which the tensor and full filters solve
  /// (coupling_set.hh); implicit Euler takes the diagonal bound k diag(w) (stiffer, so
  /// stable). Empty or -1: each node's coupling is its own.
  Eigen::VectorXi applied_group;
};

/// What node i's couplings add to the diagonal of an implicit step's system M + dt C + dt^2 K:
/// dt^2 k + dt c (0 without couplings).
template <int dim> double coupling_diagonal(const State<dim>& s, Eigen::Index i, double dt) {
  double d = 0;
  if (i < s.applied_stiffness.size()) d += dt * dt * s.applied_stiffness[i];
  if (i < s.applied_damping.size()) d += dt * s.applied_damping[i];
  return d;
}

/// The couplings' force over the step that the implicit system expects on its right-hand side
/// (as a spring's dt K v): -dt k v at node i; the damping has none (its force is at v already).
template <int dim> Vec<dim> coupling_force_correction(const State<dim>& s, Eigen::Index i, double dt) {
  if (i < s.applied_stiffness.size() && s.applied_stiffness[i] > 0) return -dt * s.applied_stiffness[i] * s.v.col(i);
  return Vec<dim>::Zero();
}

/// Initial state of a model: zero displacement, the scene's initial velocity, constraints.
template <int dim> State<dim> initial_state(const Model<dim>& model);

template <int dim> class Integrator {
public:
  explicit Integrator(double dt) : m_dt(dt) {}
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  /// Advances `s` from s.t to s.t + dt. Allocates nothing.
  virtual void step(State<dim>& s) = 0;
  virtual std::string_view name() const = 0;
  double dt() const { return m_dt; }
  /// The compliance of coupling group g (State::applied_group) in the last step's system, the
  /// coupling's own stiffness left out: how far (m) the group's weighted position w . x moves
  /// over one step per N of extra force spread on it by w, dt^2 w^T H^-1 w (dim x dim, world
  /// axes). What a haptic servo solves its contact against between physics steps
  /// (local_model.hh). False where the solver does not solve its couplings in its system
  /// (they are applied as forces alone) or g took no part in the last step.
  virtual bool coupling_compliance(int /*group*/, Eigen::Matrix<double, dim, dim>& /*out*/) const { return false; }

private:
  double m_dt;
};

/// Options that select and tune a spring solver (from [solver]).
/// What an integrator is built from: the scene's [solver] settings for the spring steppers and
/// CVODE, as they are, plus the kind and the step.
struct IntegratorOptions : SpringStepSettings, CvodeSettings {
  std::string kind = solvers::kFiltered;
  double dt = 1e-3;
  /// Set by with_budget_pick when it resolved `auto`: what was asked for and why the filter.
  std::string filter_requested, filter_reason;
};

/// From this many free nodes a 3D system is solved by the multigrid V-cycle rather than a
/// sparse factor, whose fill grows like n^(4/3) there (docs/performance.md): implicit Euler's
/// `auto` linear solver's threshold, and where a step budget stops trying the full filter.
inline constexpr std::size_t kLargeFreeNodes3D = 4000;

/// From this many free nodes a 3D tensor filter solves with its block V-cycle rather than H_t's
/// factor, whose step is no cheaper from about 600 nodes and 2.3x dearer at 1,400 (CGAL slabs,
/// docs/performance.md item 13).
inline constexpr std::size_t kTensorCycleFreeNodes3D = 1000;

/// From this many free nodes `auto` runs the scalar multigrid filter in 3D, whose step lags but
/// costs about a ninth of the block V-cycle's: beyond the sizes the lag-free default was
/// measured at (up to the 10k slab: 188 MB peak; docs/method.md, "What `auto` does with it").
inline constexpr std::size_t kScalarCycleFreeNodes3D = 12000;

/// The filter `filtered` runs for `filter` on this model: `filter` itself, or for `auto` the
/// lag-free tensor filter (2D; 3D by its factor below kTensorCycleFreeNodes3D free nodes and by
/// its block V-cycle from there) and the scalar multigrid filter on 3D meshes of
/// kScalarCycleFreeNodes3D free nodes and more (docs/method.md).
template <int dim> std::string chosen_filter(const Model<dim>& model, const std::string& filter);

/// The factory by name: explicit | filtered | implicit-euler. Throws InputError for others.
template <int dim>
std::unique_ptr<Integrator<dim>> make_integrator(const Model<dim>& model, const IntegratorOptions& options);

} // namespace vtb
