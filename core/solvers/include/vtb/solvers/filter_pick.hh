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

} // namespace vtb
