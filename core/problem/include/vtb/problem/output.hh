#pragma once
/// \file
/// Output files of `vtb run` (DESIGN.md §2): probes.csv, reactions.csv, summary.json.
/// Files are written under a temporary name and renamed only when all are complete.

#include "vtb/meshes/atomic_file.hh" // write_files_atomically, IoError
#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vtb {

template <int dim>
void write_run_outputs(const std::filesystem::path& dir, const Problem<dim>& model, const Trajectory<dim>& traj,
                       const RunReport& report, const std::string& scene_name);

/// frames.pvd listing frames/frame_NNNN.vtu with their times (the .vtu files written by the
/// caller: the spring runs with write_vtu, the FEM with deal.II's DataOut).
void write_pvd(const std::filesystem::path& dir, const std::vector<double>& times);

/// The summary as JSON text (for tests).
std::string summary_json(const RunReport& report, const std::string& scene_name);

} // namespace vtb
