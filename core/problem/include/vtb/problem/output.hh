#pragma once
/// \file
/// Output files of `vtb run` (README.md, docs/scenes.md, docs/harness.md): probes.csv, reactions.csv, summary.json.
/// Files are written under a temporary name and renamed only when all are complete.

#include "vtb/base/atomic_file.hh" // write_files_atomically, IoError
#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"

#include <array>
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

/// What a run wrote, in memory and free of the dimension: the rows of probes.csv and
/// reactions.csv (uz, fz = 0 in 2D) and the text of summary.json, the same values the files
/// hold before they are printed (what `import vtb` returns as arrays).
struct RunTables {
  int dim = 2;
  RunReport report;
  std::vector<double> probe_t, reaction_t; ///< one per row
  std::vector<std::string> probe_name, region;
  std::vector<std::array<double, 3>> probe_u, reaction_f;
  std::string summary_json; ///< summary.json's text, probes included
};

/// The tables of a trajectory (as write_run_outputs prints them).
template <int dim>
RunTables run_tables(const Problem<dim>& model, const Trajectory<dim>& traj, const RunReport& report,
                     const std::string& scene_name);

/// The end of every `run_scene`: writes the run's files into `dir` (nothing when `dir` is
/// empty: a run kept in memory) and, when `tables` is set, fills it.
template <int dim>
void finish_run(const std::filesystem::path& dir, const Problem<dim>& model, const Trajectory<dim>& traj,
                const RunReport& report, const std::string& scene_name, RunTables* tables);

} // namespace vtb
