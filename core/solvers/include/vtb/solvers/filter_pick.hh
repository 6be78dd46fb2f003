#pragma once
/// \file
/// `[solver] step_budget` (seconds per step): a cost a haptic loop can plan on. With
/// `filter = "auto"` the filtered solver runs the most accurate filter whose measured step fits
/// the budget (docs/method.md): the candidates in order of accuracy (the lag-free tensor
/// filter, by its factor or its block V-cycle, then the scalar full filter and its V-cycle;
/// each only where its size allows, as chosen_filter's thresholds say), each built and timed
/// over kTrialSteps steps from the scene's start (after kTrialWarmup untimed ones); the first whose median fits is run.
/// Where none fits, the cheapest measured, and the reason says so. Without a budget, or with a filter named, the
/// options are returned as given (chosen_filter decides auto by size alone, and the run's answers do not depend on the
/// machine's clock).

#include "vtb/solvers/integrator.hh"

namespace vtb {

/// Steps timed per candidate filter (their median is the measured cost), after untimed ones.
inline constexpr int kTrialSteps = 9;
inline constexpr int kTrialWarmup = 3;

/// `o` with `auto` resolved within o.step_budget: filter set to the pick, filter_requested to
/// "auto" and filter_reason to what was measured. Unchanged without a budget or for other kinds.
template <int dim> IntegratorOptions with_budget_pick(const Model<dim>& model, const IntegratorOptions& o);

/// A real-time haptic session's physics runs at the rate it affords: its step costs at most
/// 1 / kPhysicsHeadroom of its dt, so that it keeps pace with wall time with room for the
/// contact's solves and another process on the machine (docs/haptics.md).
inline constexpr double kPhysicsHeadroom = 2.0;
/// The longest physics step a session plans on (s): a body whose most accurate lag-free filter
/// needs more runs a cheaper filter instead, and where none fits, the cheapest at this dt.
inline constexpr double kMaxPhysicsPeriod = 0.06;

/// The contact a haptic session's trial steps carry: a coupling unit of this stiffness (N/m) and
/// damping (N s/m) spread over kTrialCouplingNodes free nodes, which costs a step what a tool
/// tip's footprint does (its Woodbury solves: twice the step of a free 10k-node slab).
struct TrialCoupling {
  double stiffness = 400, damping = 2;
};
inline constexpr int kTrialCouplingNodes = 8;

/// `o` with dt (a whole number of servo periods) and, for `auto`, the filter chosen for a real-time
/// haptic session: the most accurate candidate (with_budget_pick's order) whose measured step
/// with `coupling`, times kPhysicsHeadroom and rounded up to whole periods, is at most
/// kMaxPhysicsPeriod; a named filter or another spring solver keeps its kind and gets its own dt
/// so. filter_reason says what was measured. With `auto` resolved, filter_requested is "auto".
template <int dim>
IntegratorOptions with_physics_rate(const Model<dim>& model, const IntegratorOptions& o, double period,
                                    const TrialCoupling& coupling);

} // namespace vtb
