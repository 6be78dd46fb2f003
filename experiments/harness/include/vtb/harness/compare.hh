#pragma once
/// \file
/// `vtb compare`: run several solvers on one scene and measure each against a reference;
/// the error decomposition of docs/harness.md.

#include "vtb/harness/metrics.hh"

#include <filesystem>
#include <map>

namespace vtb::harness {

struct CompareRow {
  std::string solver;
  RunReport report;
  ErrorMetrics error; ///< against the reference
  double wall_seconds = 0;
  std::string note; ///< for fem and fem-mesh: which FEM ran
};

/// One term of the decomposition: `a` measured against `b`.
struct DecompositionRow {
  std::string a, b, meaning;
  ErrorMetrics error;
};

struct CompareResult {
  std::string scene, reference;
  std::string reference_note;           ///< for fem and fem-mesh: which FEM the reference is
  bool geometrically_exact_fem = false; ///< the FEM runs a nonlinear law ([solver].kinematics)
  /// Names of the point loads (a force on one node): under them the continuum answer is
  /// singular and the FEM reference does not converge with refinement.
  std::vector<std::string> point_loads;
  int nodes = 0;
  double duration = 0;
  std::vector<CompareRow> rows;
  std::vector<DecompositionRow> decomposition; ///< filtered vs cvode, cvode vs fem, filtered vs fem (those run)
};

/// What `compare` keeps of each run besides the table: with `runs_dir` set, each solver's
/// probes.csv, reactions.csv and summary.json in runs_dir/<solver>/, and with `frames` its
/// frames.pvd and frames/*.vtu (the same files `vtb run` writes).
struct KeepRuns {
  std::filesystem::path runs_dir;
  bool frames = false;
};

/// Runs `solvers` and the reference on the scene: `fem`, the continuum (P2 at the refinement
/// the static ladder of vtb/fem/continuum.hh found converged), `fem-mesh`, the scene's own FEM
/// (P1 on the mesh by default), or `cvode`, the springs' exact trajectory. `dt` > 0 overrides the
/// scene's step for every fixed-step solver. Progress goes to `progress` if non-null.
CompareResult run_compare(const Scene& scene, const std::vector<std::string>& solvers, const std::string& reference,
                          double dt = 0, std::ostream* progress = nullptr, const KeepRuns& keep = {});

/// compare.csv (one row per solver) and decomposition.csv; nothing is left half-written.
void write_compare(const CompareResult& result, const std::filesystem::path& dir);

/// The readable table printed by `vtb compare`.
std::string format_compare(const CompareResult& result);

} // namespace vtb::harness
