#include "vtb/solvers/filter_pick.hh"

#include "vtb/problem/solver_names.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

namespace vtb {

namespace {

/// The filters auto may pick on this model, most accurate first: the tensor filter (its
/// factor below kTensorCycleFreeNodes3D free nodes in 3D, its block V-cycle from there), then
/// the full filter (its factor, below kLargeFreeNodes3D in 3D) and its V-cycle (3D).
template <int dim> std::vector<std::string> candidates(const Model<dim>& model) {
  const std::size_t free = model.free_nodes.size();
  if constexpr (dim == 2) return {solvers::kFilterTensor, solvers::kFilterFull};
  std::vector<std::string> c;
  if (free < kTensorCycleFreeNodes3D) c.emplace_back(solvers::kFilterTensor);
  c.emplace_back(solvers::kFilterTensorMultigrid);
  if (free < kLargeFreeNodes3D) c.emplace_back(solvers::kFilterFull);
  c.emplace_back(solvers::kFilterMultigrid);
  return c;
}

/// The median of kTrialSteps steps of `filter` from the model's start (s), after kTrialWarmup.
template <int dim> double trial_step(const Model<dim>& model, IntegratorOptions o, const std::string& filter) {
  using clock = std::chrono::steady_clock;
  o.filter = filter;
  auto integ = make_integrator(model, o);
  State<dim> s = initial_state(model);
  std::vector<double> times;
  times.reserve(kTrialSteps);
  for (int k = 0; k < kTrialWarmup; ++k) { // caches and first factorisations, not timed
    integ->step(s);
    s.t += o.dt;
  }
  for (int k = 0; k < kTrialSteps; ++k) {
    const auto a = clock::now();
    integ->step(s);
    times.push_back(std::chrono::duration<double>(clock::now() - a).count());
    s.t += o.dt;
  }
  std::nth_element(times.begin(), times.begin() + kTrialSteps / 2, times.end());
  return times[kTrialSteps / 2];
}

std::string microseconds(double s) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(s >= 1e-4 ? 0 : 1) << s * 1e6 << " us";
  return os.str();
}

} // namespace

template <int dim> IntegratorOptions with_budget_pick(const Model<dim>& model, const IntegratorOptions& o) {
  if (o.kind != solvers::kFiltered || o.filter != solvers::kFilterAuto || !(o.step_budget > 0)) return o;
  IntegratorOptions picked = o;
  picked.filter_requested = o.filter;
  std::string cheapest;
  double cheapest_cost = INFINITY;
  for (const std::string& f : candidates(model)) {
    const double cost = trial_step(model, o, f);
    if (cost <= o.step_budget) {
      picked.filter = f;
      picked.filter_reason = f + "'s measured step " + microseconds(cost) + " fits the step budget of " +
                             microseconds(o.step_budget) +
                             (f == candidates(model).front() ? "" : " (the more accurate ones do not)");
      return picked;
    }
    if (cost < cheapest_cost) {
      cheapest_cost = cost;
      cheapest = f;
    }
  }
  picked.filter = cheapest;
  picked.filter_reason = "no filter's measured step fits the step budget of " + microseconds(o.step_budget) +
                         ": the cheapest, " + cheapest + ", at " + microseconds(cheapest_cost);
  return picked;
}

template IntegratorOptions with_budget_pick<2>(const Model<2>&, const IntegratorOptions&);
template IntegratorOptions with_budget_pick<3>(const Model<3>&, const IntegratorOptions&);

} // namespace vtb
