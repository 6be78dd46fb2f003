#pragma once
/// \file
/// `vtb reproduce`: the paper's experiment and timing table on the 517- and 123-node plates,
/// the Fig. 3 analogue, accuracy against speed, the stability map, and a markdown report.

#include <filesystem>
#include <iosfwd>

namespace vtb::harness {

struct ReproduceOptions {
  bool quick = false;               ///< 2 s of simulated time instead of 10, smaller ladders
  std::filesystem::path out;        ///< output folder
  std::filesystem::path scenes_dir; ///< where plate517_step.toml etc. live
  std::ostream* progress = nullptr;
};

/// Writes timing_table.csv, fig3/*.csv|vtu, accuracy_speed.csv, stability.csv,
/// decomposition.csv and report.md into options.out; returns the report's text.
std::string run_reproduce(const ReproduceOptions& options);

} // namespace vtb::harness
