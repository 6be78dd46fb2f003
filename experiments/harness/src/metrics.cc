#include "vtb/harness/metrics.hh"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vtb::harness {

namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();

/// e / scale, 0 when both vanish, NaN for an error against a zero reference.
double ratio(double e, double scale) {
  return scale > 0 ? e / scale : (e > 0 ? kNan : 0.0);
}

/// The displacement field's errors over n samples: all nodes, and the nodes `away` marks.
template <int dim>
void field_errors(const Trajectory<dim>& a, const Trajectory<dim>& ref, std::size_t n, const std::vector<char>* away,
                  ErrorMetrics& m) {
  if (a.field.empty() || ref.field.empty()) {
    m.displacement_max = m.displacement_final = kNan;
    return;
  }
  double scale = 0;
  for (const auto& f : ref.field) scale = std::max(scale, f.norm());
  for (std::size_t k = 0; k < n; ++k) {
    const double e = ratio((a.field[k] - ref.field[k]).norm(), scale);
    m.displacement_max = std::max(m.displacement_max, e);
    if (k + 1 == n) m.displacement_final = e;
  }
  if (!away) return;
  auto masked = [&](const Nodal<dim>& f) {
    double s = 0;
    for (Eigen::Index i = 0; i < f.cols(); ++i)
      if ((*away)[static_cast<std::size_t>(i)]) s += f.col(i).squaredNorm();
    return std::sqrt(s);
  };
  double away_scale = 0;
  for (const auto& f : ref.field) away_scale = std::max(away_scale, masked(f));
  m.displacement_away_max = 0;
  for (std::size_t k = 0; k < n; ++k)
    m.displacement_away_max = std::max(m.displacement_away_max, ratio(masked(a.field[k] - ref.field[k]), away_scale));
}

template <int dim>
void probe_errors(const Trajectory<dim>& a, const Trajectory<dim>& ref, std::size_t n, ErrorMetrics& m) {
  double scale = 0;
  for (const auto& s : ref.probe_u)
    for (const auto& u : s) scale = std::max(scale, u.norm());
  for (std::size_t k = 0; k < n; ++k) {
    double e = 0;
    for (std::size_t p = 0; p < ref.probe_u[k].size(); ++p)
      e = std::max(e, (a.probe_u[k][p] - ref.probe_u[k][p]).norm());
    e = ratio(e, scale);
    m.probe_max = std::max(m.probe_max, e);
    if (k + 1 == n) m.probe_final = e;
  }
}

template <int dim>
void reaction_errors(const Trajectory<dim>& a, const Trajectory<dim>& ref, std::size_t n, ErrorMetrics& m) {
  auto stack_norm = [](const std::vector<Vec<dim>>& r) {
    double s = 0;
    for (const auto& v : r) s += v.squaredNorm();
    return std::sqrt(s);
  };
  double scale = 0;
  for (const auto& r : ref.reaction) scale = std::max(scale, stack_norm(r));
  for (std::size_t k = 0; k < n; ++k) {
    std::vector<Vec<dim>> d = a.reaction[k];
    for (std::size_t q = 0; q < d.size(); ++q) d[q] -= ref.reaction[k][q];
    const double e = ratio(stack_norm(d), scale);
    m.reaction_max = std::max(m.reaction_max, e);
    if (k + 1 == n) m.reaction_final = e;
  }
}

} // namespace

template <int dim>
ErrorMetrics compare(const Trajectory<dim>& a, const Trajectory<dim>& ref, const std::vector<char>* away) {
  ErrorMetrics m;
  const std::size_t n = std::min(a.t.size(), ref.t.size());
  m.compared = n;
  if (n == 0) return m;
  for (std::size_t k = 0; k < n; ++k)
    if (std::abs(a.t[k] - ref.t[k]) > 1e-9 * std::max(1.0, std::abs(ref.t[k])))
      throw std::invalid_argument("compare: sample " + std::to_string(k) + " is at t = " + std::to_string(a.t[k]) +
                                  " in one run and " + std::to_string(ref.t[k]) + " in the reference");
  field_errors(a, ref, n, away, m);
  probe_errors(a, ref, n, m);
  reaction_errors(a, ref, n, m);
  return m;
}

template <int dim> std::vector<char> away_from_loads(const Model<dim>& model) {
  double longest = 0;
  for (const double l : model.net.rest_length) longest = std::max(longest, l);
  std::vector<int> loaded;
  for (const auto& l : model.loads) loaded.insert(loaded.end(), l.nodes.begin(), l.nodes.end());
  std::vector<char> away(static_cast<std::size_t>(model.num_nodes()), 1);
  for (int i = 0; i < model.num_nodes(); ++i)
    for (int j : loaded)
      if ((model.mesh.points.col(i) - model.mesh.points.col(j)).norm() <= 2 * longest) {
        away[static_cast<std::size_t>(i)] = 0;
        break;
      }
  return away;
}

template ErrorMetrics compare<2>(const Trajectory<2>&, const Trajectory<2>&, const std::vector<char>*);
template ErrorMetrics compare<3>(const Trajectory<3>&, const Trajectory<3>&, const std::vector<char>*);
template std::vector<char> away_from_loads<2>(const Model<2>&);
template std::vector<char> away_from_loads<3>(const Model<3>&);

} // namespace vtb::harness
