#pragma once
/// \file
/// The physics behind `vtb view` and the Python module's `vtb.Simulation` (its own target,
/// `vtb::live_sim`, free of any window): one spring solver advancing a scene at its fixed dt,
/// decoupled from the frame rate (substeps within a wall-time budget), with forces applied
/// by hand (pulls through a virtual coupling) or set from outside between steps, live solver
/// switching, and a watch that catches a diverging solver instead of dying with it.
/// Allocation-free per step; the state's u and v keep their storage for the simulation's life
/// (reset and reconfiguring copy into it), so views of them stay valid.

#include "vtb/problem/scene.hh"
#include "vtb/problem/solver_registry.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/stepper/trace_ring.hh"

#include "vtb/solvers/coupling_set.hh"

#include <array>
#include <memory>
#include <optional>
#include <string>

namespace vtb {

/// The solvers that can run interactively (one step at a time): the fixed-step spring
/// integrators. cvode and fem produce whole trajectories and are run by `vtb run`/`compare`.
/// Read from the registry (its `interactive` flag).
inline std::vector<std::string> interactive_solvers() {
  return solvers::names(solvers::is_stepper);
}
using solvers::kFilterChoices;
/// The spring calibrations ([solver].springs); "fitted" fits once per mesh, Poisson ratio and
/// supports (cached); "auto" fits within its budget, else Lloyd.
inline constexpr std::array<const char*, 9> kSprings = {"auto",          "lloyd",         "van-gelder",
                                                        "fitted",        "volume",        "nodal-volume",
                                                        "fitted-volume", "fitted-stable", "fitted-nodal"};

/// What the panel controls; applying it rebuilds the model and the integrator.
struct SimControls {
  std::string solver = solvers::kFiltered;
  std::string filter = solvers::kFilterAuto;
  double dt = 1e-3;
  double stiffness_scale = 1.0;
  std::string springs = "auto"; ///< the calibration requested (the model's net says which it used)
};

/// A hand pull: the grabbed patch is pulled toward `target` by a spring of stiffness k (N/m).
/// The patch is the boundary nodes within the grab radius of `node` at rest (the scene's tool
/// tip, docs/haptics.md; just `node` in 2D or inside the body), the nearest kMaxNodes,
/// weighted equally: the spring acts on their mean position and spreads its force by the
/// weights, as a tool holding a patch of tissue does, where a single node was dragged into a
/// spike.
template <int dim> struct Pull {
  static constexpr int kMaxNodes = CouplingSet<dim>::kMaxUnits;
  int node = -1;
  Vec<dim> target = Vec<dim>::Zero();
  bool pinned = false;
  int count = 0; ///< the patch's nodes
  std::array<int, kMaxNodes> nodes{};
  std::array<double, kMaxNodes> weights{};
};

/// Rolling readouts of the run.
struct SimStats {
  double step_median_us = 0;  ///< over the last steps
  double realtime_factor = 0; ///< simulated / wall seconds over the last frame
  bool behind = false;        ///< the last frame could not keep up with real time
  double energy = 0;          ///< elastic + kinetic, J
  double max_strain = 0;      ///< max |l/L0 - 1|
  long steps = 0;
  long fallback_steps = 0;    ///< tensor filter: steps handed to implicit Euler (distortion past trust)
  double step_budget_us = 0;  ///< [solver].step_budget (0: none)
  long steps_over_budget = 0; ///< steps that took longer, since the integrator was built
  std::string filter_reason;  ///< why auto picked the filter within the budget (empty: no budget)
};

/// Called before every step with the state whose applied forces (and their couplings'
/// stiffness and damping, State::applied_stiffness, applied_damping) already hold the pulls:
/// adds its own, e.g. the device's contact force and coupling; and after it, with the state it
/// reached and the integrator that took it (its coupling compliance: local_model.hh). Must not
/// allocate.
template <int dim> class StepHook {
public:
  virtual ~StepHook() = default;
  virtual void before_step(const Model<dim>& model, State<dim>& s, double dt) = 0;
  virtual void after_step(const Model<dim>& model, const State<dim>& s, const Integrator<dim>& integrator) = 0;
};

template <int dim> class LiveSim {
public:
  static constexpr int kMaxPulls = 8;
  static constexpr int kTrace = 600; ///< probe samples kept (the last seconds at 1 per step group)

  /// Builds the model of the scene's mesh; throws InputError for a scene the solvers refuse.
  /// `yardstick`: what the springs' load check measures against (build_model; the viewer's
  /// CLI gives the continuum, tests may leave P1 on the mesh).
  LiveSim(const Scene& scene, Mesh<dim> mesh, SimControls controls, Yardstick yardstick = {});

  /// Applies new controls (solver, filter, dt, stiffness): InputError if they are refused
  /// (the previous configuration is kept); the state is kept when the model is unchanged.
  void configure(const SimControls& controls);
  const SimControls& controls() const { return m_controls; }
  /// The filter the filtered solver runs (`auto` resolved for this model); empty for the
  /// other solvers.
  const std::string& running_filter() const { return m_running_filter; }

  /// Advances the simulated time by up to `sim_seconds` in steps of dt, stopping early when
  /// the steps have taken `wall_budget` seconds of wall time (then stats().behind is set). A dt
  /// longer than the calls' `sim_seconds` (a large body's haptic rate) is stepped once their sum
  /// reaches it.
  void advance(double sim_seconds, double wall_budget);
  /// Exactly one step (when paused); nothing once unstable.
  void single_step();
  /// `n` steps, whatever their wall time (stopping at a failure: a non-finite state at once, a
  /// runaway strain within kStrainCheckSteps steps); only the step count and the
  /// real-time factor of stats() follow (refresh_stats() updates the rest, which costs a pass
  /// over the springs). Returns the steps taken.
  long steps(long n);
  /// Brings stats() up to date: the step median, energy, max strain, fallback steps (advance()
  /// does it at the end of every call).
  void refresh_stats();
  void reset();

  /// Pulls: add one at the node, grabbing the patch of the grab radius around it (Pull;
  /// returns its index, or -1 when all slots are used).
  int add_pull(int node, const Vec<dim>& target, bool pinned = false);
  void move_pull(int index, const Vec<dim>& target);
  void remove_pull(int index);
  void clear_unpinned();
  int num_pulls() const { return m_num_pulls; }
  const Pull<dim>& pull(int k) const { return m_pulls[static_cast<std::size_t>(k)]; }
  /// The force the pull exerts on the body now, N.
  Vec<dim> pull_force(int k) const;
  double coupling_stiffness = 0; ///< N/m, set from the network's stiffness at construction
  /// Forces set from outside between steps (a script's controller, a user's device loop), per
  /// node, added to the pulls' at every step until changed; with, per node, the stiffness
  /// (N/m) and damping (N s/m) of the coupling that makes them (0 for a plain force), which the
  /// implicit solvers take implicitly as they do a pull's. Sized to the mesh; kept across
  /// configure and reset.
  Nodal<dim>& external_force() { return m_external_force; }
  Eigen::VectorXd& external_stiffness() { return m_external_stiffness; }
  Eigen::VectorXd& external_damping() { return m_external_damping; }
  /// The hook called before each step (not owned; nullptr for none).
  void set_hook(StepHook<dim>* hook) { m_hook = hook; }

  const Model<dim>& model() const { return *m_model; }
  const State<dim>& state() const { return m_state; }
  /// Current positions X + u.
  Vec<dim> position(int node) const { return m_model->net.rest.col(node) + m_state.u.col(node); }
  /// Where pull k holds the body now: its patch's weighted mean position.
  Vec<dim> grabbed(int k) const;
  /// The radius of the patch a pull grabs (m): the scene's tool tip.
  double grab_radius() const { return m_grab_radius; }
  const SimStats& stats() const { return m_stats; }
  /// The explicit scheme's predicted stability limit for the current model (s).
  double courant_dt() const { return m_courant_dt; }
  /// Empty while the run is sound; else what went wrong and when.
  const std::string& failure() const { return m_failure; }
  /// The first probe's displacement magnitude over the last kTrace samples (oldest first),
  /// written into `out`; returns the count.
  int probe_trace(float* out) const;
  const std::string& probe_name() const { return m_probe_name; }

private:
  void rebuild();
  void step_once();
  /// After each step: a non-finite state is a failure at once; a runaway strain (a pass over
  /// the springs) is looked for every kStrainCheckSteps steps and when a call ends.
  void check(bool strain_now);
  static constexpr int kStrainCheckSteps = 16;
  void restart(); ///< the model's initial state, copied into the state's storage

  Scene m_scene;
  Mesh<dim> m_mesh;
  Yardstick m_yardstick;
  SimControls m_controls;
  std::unique_ptr<Model<dim>> m_model;
  std::unique_ptr<Integrator<dim>> m_integ;
  State<dim> m_state;
  Nodal<dim> m_external_force;
  Eigen::VectorXd m_external_stiffness, m_external_damping;
  std::array<Pull<dim>, kMaxPulls> m_pulls{};
  int m_num_pulls = 0;
  double m_grab_radius = 0;
  std::vector<char> m_on_boundary; ///< per node: on the mesh's boundary
  SimStats m_stats;
  std::string m_failure;
  std::array<double, 256> m_step_us{};
  int m_step_count = 0;
  TraceRing<kTrace> m_trace; ///< the first probe's |u|
  int m_probe_node = -1;
  double m_courant_dt = 0;
  StepHook<dim>* m_hook = nullptr;
  double m_owed = 0; ///< s of simulated time asked for and not yet stepped, below one dt
  std::string m_probe_name;
  std::string m_running_filter; ///< what the filtered solver runs (auto resolved)
};

} // namespace vtb
