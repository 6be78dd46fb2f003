#pragma once
/// \file
/// What every solver reports, spring or FEM: the trajectory sampled at the scene's times, the
/// step statistics, the run report (summary.json), and the sample schedule they share.

#include "vtb/linalg/nodal.hh"

#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace vtb {

/// What the loop records at each sample time.
template <int dim> struct Trajectory {
  std::vector<double> t;
  std::vector<std::vector<Vec<dim>>> probe_u;  ///< [sample][probe]
  std::vector<std::vector<Vec<dim>>> reaction; ///< [sample][support]: force the support exerts on the body
  std::vector<Nodal<dim>> field;               ///< [sample] all displacements, when asked for
  std::vector<Nodal<dim>> velocity;            ///< [sample] all velocities, with the field (spring solvers)
};

struct StepStats {
  double mean = 0, median = 0, p99 = 0; ///< seconds per step
};

/// Mean, median and 99th percentile (the sample at floor(q n)) of per-step wall times.
StepStats step_stats(std::vector<double> seconds);

/// The outcome of one run; what summary.json reports.
struct RunReport {
  std::string solver;
  int dim = 2;
  int nodes = 0, springs = 0, free_nodes = 0;
  double dt = 0, duration = 0;
  long steps = 0, steps_taken = 0;
  double precompute_seconds = 0;
  StepStats step_seconds;
  double total_seconds = 0; ///< wall time of the whole time loop (steps, samples, checks)
  bool stable = true;
  std::string failure;      ///< why the run was stopped, empty when stable
  double failure_time = -1; ///< simulated time of the failure
  double max_strain = 0;   ///< max over samples of the largest principal small strain (max_small_strain; the FEM's too)
  double max_rotation = 0; ///< max over samples of the largest cell rotation, radians (max_rotation; the FEM's too)
  double max_spring_strain = 0; ///< spring solvers: max over samples of max |l/L0 - 1| (the runaway watch's measure)
  double courant_dt = 0;        ///< predicted stability limit of the explicit scheme (estimate)
  std::string calibration;      ///< spring solvers: the constants used (lloyd, van-gelder, fitted)
  std::string calibration_requested;  ///< the scene's [solver].springs (auto, or one of the above)
  double calibration_seconds = 0;     ///< spring solvers: the stiffness calibration's wall time (the fit, for "fitted")
  bool calibration_cached = false;    ///< a fit's constants read from the fit cache instead of fitted
  bool calibration_own_loads = false; ///< the fit trained on the scene's own loads (SpringNetwork's)
  double calibration_validation = std::numeric_limits<double>::quiet_NaN(); ///< the fit's held-out error, if one ran
  /// Spring solvers: the springs' linear static error on the scene's own loads against the
  /// yardstick (the continuum, else P1 FEM on the mesh; load_check.hh), if measured.
  double calibration_load_error = std::numeric_limits<double>::quiet_NaN();
  double mesh_fem_load_error = std::numeric_limits<double>::quiet_NaN(); ///< P1 on the mesh against the continuum
  std::string calibration_yardstick; ///< what calibration_load_error is measured against
  std::string calibration_target;    ///< what a fit was trained on: the continuum or P1 on the mesh
  std::string calibration_note; ///< why the constants are not what was asked for (auto's fallback, the fit's guard)
  double effective_poisson_ratio = 0;
  std::string filter;           ///< filtered: the filter it ran
  std::string filter_requested; ///< filtered: the scene's [solver].filter (auto, or the filter itself)
  std::string filter_reason;    ///< filtered: why auto picked it within the step budget (empty: no budget)
  double step_budget = 0;       ///< [solver].step_budget (s; 0: none)
  long steps_over_budget = 0;   ///< the steps that took longer
  /// filtered: what took most of the steps: the filter, or implicit-euler where the tensor
  /// filter's safety net took more than half of them (then the step cost is implicit Euler's).
  std::string filter_most_steps;
  long fallback_steps = 0; ///< filtered (tensor): the steps implicit Euler took
  bool momentum_correction = false;
  double strain_limit = 0;
  /// Solver-specific figures for summary.json (e.g. the FEM's cells, dofs, phase times).
  std::vector<std::pair<std::string, double>> extra;
};

/// The times every solver records at: 0, I, 2I, ... up to the duration D, and D itself when
/// it is not a multiple of I (within 1e-9 of I). Shared by the spring solvers, CVODE and the
/// FEM, so that their trajectories line up sample for sample whatever their steps.
std::vector<double> sample_times(double duration, double interval);

/// A fixed-step loop's progress through sample_times(duration, interval) (sample 0, at t = 0,
/// is taken before the first step): whether the step ending at t1 contains the next sample
/// time, and the sample times it contains.
class SampleSchedule {
public:
  SampleSchedule(double duration, double interval) : m_times(sample_times(duration, interval)) {}
  std::size_t size() const { return m_times.size(); }
  bool due(double t1, double dt) const { return m_next < m_times.size() && m_times[m_next] <= t1 + 1e-9 * dt; }
  /// The sample times in the step ending at t1, and the loop moves past them.
  std::span<const double> take(double t1, double dt) {
    const std::size_t first = m_next;
    while (due(t1, dt)) ++m_next;
    return {m_times.data() + first, m_next - first};
  }

private:
  std::vector<double> m_times;
  std::size_t m_next = 1;
};

/// The weight of the state at t1 in the sample at ts of the step [t0, t1]: (ts - t0)/(t1 - t0),
/// and exactly 1 within 1e-9 of the step of t1 (the state at t1 itself, bit for bit).
inline double step_weight(double t0, double t1, double ts) {
  return t1 - ts <= 1e-9 * (t1 - t0) ? 1.0 : (ts - t0) / (t1 - t0);
}

/// A fixed-step solver recorded its state at both ends of one step, t0 and t1 (the last two
/// samples of traj); replaces them by the samples at `times`, each in [t0, t1], by
/// linear interpolation of every recorded quantity (probes, reactions, field). A time within
/// 1e-9 (t1 - t0) of t1 takes the state at t1 exactly.
template <int dim> void interpolate_last_step(Trajectory<dim>& traj, std::span<const double> times);

} // namespace vtb
