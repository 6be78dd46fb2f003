#pragma once
/// \file
/// Output files of `vtb run` (DESIGN.md §2): probes.csv, reactions.csv, summary.json.
/// Files are written under a temporary name and renamed only when all are complete.

#include "vtb/core/simulation.hh"

#include <filesystem>

namespace vtb {

template <int dim>
void write_run_outputs(const std::filesystem::path& dir, const Model<dim>& model, const Trajectory<dim>& traj,
                       const RunReport& report, const std::string& scene_name);

/// The summary as JSON text (for tests).
std::string summary_json(const RunReport& report, const std::string& scene_name);

} // namespace vtb
