#pragma once
/// \file
/// Error metrics between two trajectories sampled at the same times.

#include "vtb/core/simulation.hh"

namespace vtb::harness {

/// Relative errors against a reference (the maximum over time is the headline number):
/// - displacement: e(t) = ||u(t) - u_ref(t)||_2 over all nodes / max_t ||u_ref(t)||_2,
/// - probes: max over probes of |u - u_ref| / max over time and probes of |u_ref|,
/// - reactions: ||R(t) - R_ref(t)|| over all supports / max_t ||R_ref(t)||.
/// `compared` is the number of common samples (fewer when a run stopped early); a metric
/// whose reference scale is zero is reported as NaN.
struct ErrorMetrics {
  double displacement_max = 0, displacement_final = 0;
  double probe_max = 0, probe_final = 0;
  double reaction_max = 0, reaction_final = 0;
  std::size_t compared = 0;
};

/// Throws std::invalid_argument if the sample times differ (beyond 1e-9 relative).
template <int dim> ErrorMetrics compare(const Trajectory<dim>& run, const Trajectory<dim>& reference);

} // namespace vtb::harness
