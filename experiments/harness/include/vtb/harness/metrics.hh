#pragma once
/// \file
/// Error metrics between two trajectories sampled at the same times.

#include "vtb/solvers/simulation.hh"

#include <limits>
#include <vector>

namespace vtb::harness {

/// Relative errors against a reference (the maximum over time is the headline number):
/// - displacement: e(t) = ||u(t) - u_ref(t)||_2 over all nodes / max_t ||u_ref(t)||_2,
/// - probes: max over probes of |u - u_ref| / max over time and probes of |u_ref|,
/// - reactions: ||R(t) - R_ref(t)|| over all supports / max_t ||R_ref(t)||.
/// - displacement away from the loads: the same over the nodes `away` marks (those farther
///   than two of the mesh's longest edges from every loaded node: where the continuum answer
///   of a point load is regular; away_from_loads), NaN when no mask is given.
/// `compared` is the number of common samples (fewer when a run stopped early); a metric
/// whose reference scale is zero is reported as NaN.
struct ErrorMetrics {
  double displacement_max = 0, displacement_final = 0;
  double displacement_away_max = std::numeric_limits<double>::quiet_NaN();
  double probe_max = 0, probe_final = 0;
  double reaction_max = 0, reaction_final = 0;
  std::size_t compared = 0;
};

/// Throws std::invalid_argument if the sample times differ (beyond 1e-9 relative).
template <int dim>
ErrorMetrics compare(const Trajectory<dim>& run, const Trajectory<dim>& reference,
                     const std::vector<char>* away = nullptr);

/// Per node: 1 if it lies farther than two longest edges from every node a load acts on.
template <int dim> std::vector<char> away_from_loads(const Model<dim>& model);

} // namespace vtb::harness
