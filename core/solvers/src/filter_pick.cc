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

/// The filters auto may pick on this model, most accurate first: the tensor filter (in 3D its
/// factor below kTensorCycleFreeNodes3D free nodes, its block V-cycle from there), then the
/// full filter (in 3D its factor below kLargeFreeNodes3D) and its V-cycle (3D). The tensor
/// filter has no cell blocks for the volume term (chosen_filter): with it, the scalar ones alone.
template <int dim> std::vector<std::string> candidates(const Model<dim>& model) {
  const std::size_t free = model.free_nodes.size();
  const bool tensor = model.net.volume.empty();
  std::vector<std::string> c;
  if (tensor && (dim == 2 || free < kTensorCycleFreeNodes3D)) c.emplace_back(solvers::kFilterTensor);
  if (tensor && dim == 3) c.emplace_back(solvers::kFilterTensorMultigrid);
  if (dim == 2 || free < kLargeFreeNodes3D) c.emplace_back(solvers::kFilterFull);
  if (dim == 3) c.emplace_back(solvers::kFilterMultigrid);
  return c;
}

/// The median of kTrialSteps steps of `filter` from the model's start (s), after kTrialWarmup;
/// with `coupling`, a coupling unit of kTrialCouplingNodes free nodes of that stiffness and
/// damping in every step (what a haptic contact adds to a step: its solves through Woodbury's
/// identity, made again as the nodes turn).
template <int dim>
double trial_step(const Model<dim>& model, IntegratorOptions o, const std::string& filter,
                  const TrialCoupling* coupling = nullptr) {
  using clock = std::chrono::steady_clock;
  o.filter = filter;
  auto integ = make_integrator(model, o);
  State<dim> s = initial_state(model);
  if (coupling) {
    const auto n = model.num_nodes();
    s.applied = Nodal<dim>::Zero(dim, n);
    s.applied_stiffness = Eigen::VectorXd::Zero(n);
    s.applied_damping = Eigen::VectorXd::Zero(n);
    s.applied_group = Eigen::VectorXi::Constant(n, -1);
    const std::size_t count = std::min<std::size_t>(kTrialCouplingNodes, model.free_nodes.size());
    for (std::size_t p = 0; p < count; ++p) {
      const int i = model.free_nodes[p * (model.free_nodes.size() / count)];
      s.applied_stiffness[i] = coupling->stiffness / static_cast<double>(count);
      s.applied_damping[i] = coupling->damping / static_cast<double>(count);
      s.applied_group[i] = 0;
      s.applied.col(i).setConstant(1e-3);
    }
  }
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

template <int dim>
IntegratorOptions with_physics_rate(const Model<dim>& model, const IntegratorOptions& o, double period,
                                    const TrialCoupling& coupling) {
  IntegratorOptions picked = o;
  const bool pick = o.kind == solvers::kFiltered && o.filter == solvers::kFilterAuto;
  const std::vector<std::string> names = pick ? candidates(model) : std::vector<std::string>{o.filter};
  IntegratorOptions trial = o;
  // The physics' dt for a measured step: whole servo periods, kPhysicsHeadroom times the cost.
  const auto dt_for = [&](double cost) { return period * std::max(1.0, std::ceil(kPhysicsHeadroom * cost / period)); };
  std::string chosen;
  double chosen_cost = INFINITY;
  for (const std::string& f : names) {
    // A step's cost depends on its dt (a longer step leaves the V-cycle and the tensor filter's
    // correction more to do: at 20k nodes 2-3x): timed at the servo's period, then again at the
    // dt that gave, and the dearer of the two is planned on.
    trial.dt = period;
    double cost = trial_step(model, trial, f, &coupling);
    if (dt_for(cost) > period * (1 + 1e-9) && dt_for(cost) <= 2 * kMaxPhysicsPeriod) {
      trial.dt = dt_for(cost);
      cost = std::max(cost, trial_step(model, trial, f, &coupling));
    }
    const bool fits = dt_for(cost) <= kMaxPhysicsPeriod * (1 + 1e-9);
    if (fits || cost < chosen_cost) {
      chosen = f;
      chosen_cost = cost;
    }
    if (fits) break;
  }
  picked.dt = std::min(dt_for(chosen_cost), period * std::max(1.0, std::floor(kMaxPhysicsPeriod / period + 1e-9)));
  if (pick) {
    picked.filter_requested = o.filter;
    picked.filter = chosen;
  }
  const bool fits = dt_for(chosen_cost) <= picked.dt * (1 + 1e-9);
  std::ostringstream reason;
  reason << (pick ? chosen : std::string(o.kind == solvers::kFiltered ? o.filter : o.kind)) << "'s measured step "
         << microseconds(chosen_cost) << ": the physics steps every " << microseconds(picked.dt) << " ("
         << std::lround(picked.dt / period) << " servo periods"
         << (fits ? ", at least " + std::to_string(static_cast<int>(kPhysicsHeadroom)) + "x its cost)"
                  : "; it cannot keep pace with wall time)")
         << (pick && chosen != names.front()
                 ? "; the more accurate filters do not fit " + microseconds(kMaxPhysicsPeriod)
                 : "");
  picked.filter_reason = reason.str();
  return picked;
}

template IntegratorOptions with_physics_rate<2>(const Model<2>&, const IntegratorOptions&, double,
                                                const TrialCoupling&);
template IntegratorOptions with_physics_rate<3>(const Model<3>&, const IntegratorOptions&, double,
                                                const TrialCoupling&);
template IntegratorOptions with_budget_pick<2>(const Model<2>&, const IntegratorOptions&);
template IntegratorOptions with_budget_pick<3>(const Model<3>&, const IntegratorOptions&);

} // namespace vtb
