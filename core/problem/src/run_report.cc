#include "vtb/problem/run_report.hh"

#include <algorithm>
#include <cmath>

namespace vtb {

std::vector<double> sample_times(double duration, double interval) {
  std::vector<double> t;
  const long n = static_cast<long>(std::floor(duration / interval + 1e-9));
  for (long k = 0; k <= n; ++k) t.push_back(std::min(duration, static_cast<double>(k) * interval));
  if (duration - t.back() > 1e-9 * interval) t.push_back(duration);
  return t;
}

template <int dim> void interpolate_last_step(Trajectory<dim>& traj, std::span<const double> times) {
  const std::size_t n = traj.t.size();
  const std::size_t a = n - 2, b = n - 1;
  const double t0 = traj.t[a], t1 = traj.t[b];
  Trajectory<dim> out;
  for (const double ts : times) {
    const double w = step_weight(t0, t1, ts);
    auto mix = [&](const auto& x, const auto& y) {
      using T = std::decay_t<decltype(x)>;
      return w == 1.0 ? T(y) : T((1 - w) * x + w * y);
    };
    out.t.push_back(ts);
    std::vector<Vec<dim>> pu(traj.probe_u[a].size()), re(traj.reaction[a].size());
    for (std::size_t i = 0; i < pu.size(); ++i) pu[i] = mix(traj.probe_u[a][i], traj.probe_u[b][i]);
    for (std::size_t i = 0; i < re.size(); ++i) re[i] = mix(traj.reaction[a][i], traj.reaction[b][i]);
    out.probe_u.push_back(std::move(pu));
    out.reaction.push_back(std::move(re));
    if (traj.field.size() == n) out.field.push_back(mix(traj.field[a], traj.field[b]));
    if (traj.velocity.size() == n) out.velocity.push_back(mix(traj.velocity[a], traj.velocity[b]));
  }
  const bool fields = traj.field.size() == n, velocities = traj.velocity.size() == n;
  for (int drop = 0; drop < 2; ++drop) {
    traj.t.pop_back();
    traj.probe_u.pop_back();
    traj.reaction.pop_back();
    if (fields) traj.field.pop_back();
    if (velocities) traj.velocity.pop_back();
  }
  for (std::size_t i = 0; i < times.size(); ++i) {
    traj.t.push_back(out.t[i]);
    traj.probe_u.push_back(std::move(out.probe_u[i]));
    traj.reaction.push_back(std::move(out.reaction[i]));
    if (fields) traj.field.push_back(std::move(out.field[i]));
    if (velocities) traj.velocity.push_back(std::move(out.velocity[i]));
  }
}

template void interpolate_last_step<2>(Trajectory<2>&, std::span<const double>);
template void interpolate_last_step<3>(Trajectory<3>&, std::span<const double>);

StepStats step_stats(std::vector<double> t) {
  StepStats s;
  if (t.empty()) return s;
  double sum = 0;
  for (double x : t) sum += x;
  s.mean = sum / static_cast<double>(t.size());
  auto at = [&t](double q) {
    const auto k = static_cast<std::size_t>(
        std::min<double>(static_cast<double>(t.size() - 1), std::floor(q * static_cast<double>(t.size()))));
    std::nth_element(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(k), t.end());
    return t[k];
  };
  s.median = at(0.5);
  s.p99 = at(0.99);
  return s;
}

} // namespace vtb
