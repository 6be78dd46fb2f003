#pragma once
/// \file
/// `vtb sweep`: a stability map over time step and stiffness scale.

#include "vtb/harness/metrics.hh"

#include <filesystem>
#include <iosfwd>

namespace vtb::harness {

/// One cell of the map. A run is classified stable when it finished with a finite state and
/// every sampled strain stayed at or below 1000 % (vtb's runaway criterion); the error is
/// the maximum relative L2 displacement error against CVODE at the same stiffness.
struct SweepCell {
  std::string solver;
  double dt = 0, stiffness_scale = 1, young_modulus = 0;
  bool stable = false;
  std::string failure;
  double max_strain = 0, error = 0, step_median = 0, courant_dt = 0;
};

inline constexpr const char* kStabilityCriterion =
    "finite state every step and max spring strain <= 1000% at 20 samples over the run";

/// Each requested dt is rounded down so that 1/20 of the duration is a whole number of steps
/// (the cells' sample times then match CVODE's); the dt used is reported. Under mpirun, with
/// `across_ranks`, every rank calls it and the cells are spread over the ranks (rank 0 gets all
/// of them; ranks.hh); without, this rank runs the whole sweep (a part of a job it runs alone).
std::vector<SweepCell> run_sweep(const Scene& scene, const std::vector<double>& dts, const std::vector<double>& scales,
                                 const std::vector<std::string>& solvers, std::ostream* progress = nullptr,
                                 bool across_ranks = true);

/// The solvers a sweep maps when none are named: the explicit scheme, the paper's neighbour
/// filter, the full filter and implicit Euler (where each one's stability ends).
std::vector<std::string> default_sweep_solvers();
void write_sweep(const std::vector<SweepCell>& cells, const std::filesystem::path& file);

} // namespace vtb::harness
