#pragma once
/// \file
/// `vtb study SCENE`: accuracy against cost on any scene. Every fixed-step solver over a dt
/// ladder, CVODE over an rtol ladder, each measured against one converged reference run, and
/// the Pareto front of error against wall time per simulated second.

#include "vtb/problem/scene.hh"
#include "vtb/problem/solver_names.hh"

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace vtb::harness {

struct StudyOptions {
  std::vector<std::string> solvers = {solvers::kFilteredFull, solvers::kFilteredNeighbors, solvers::kImplicitEuler,
                                      solvers::kExplicit, solvers::kCvode};
  std::string reference = solvers::kFem; ///< fem: P2 with one refinement at dt / 4; cvode: rtol 1e-10
  bool quick = false;                    ///< shorter ladders
};

struct StudyRow {
  std::string solver;
  double dt = 0;   ///< the step (fixed-step solvers; CVODE: its mean step)
  double rtol = 0; ///< cvode
  bool stable = true;
  bool skipped = false; ///< not run: `failure` says why (e.g. the explicit step makes it too long)
  std::string failure;
  double error_all = 0, error_probes = 0; ///< max over time of the relative L2 error, all nodes / probes
  double step_median = 0, total_seconds = 0;
  double cost = 0; ///< wall seconds per simulated second
  bool pareto = false;
};

struct StudyResult {
  std::string scene, reference;
  std::string filter = solvers::kFilterFull; ///< the scene's filter: what the solver `filtered` means
  int nodes = 0;
  double duration = 0;
  std::string reference_note; ///< what the reference run was
  std::vector<StudyRow> rows;
};

/// The dt ladder of a fixed-step solver: the scene's dt times 4, 2, 1, 1/2, 1/4, 1/8 (quick:
/// 4, 1, 1/4); the explicit scheme's is 0.9 and 0.45 of its stability limit instead (quick:
/// 0.9; beyond the limit every run diverges). A run of more than 2e6 steps (quick: 2e5) is
/// skipped with the count said, not run for hours (a damped plate's explicit limit is ~1e-8 s).
std::vector<double> dt_ladder(double scene_dt, bool quick);
/// CVODE's rtol ladder: 1e-3 ... 1e-7 (quick: 1e-3, 1e-5).
std::vector<double> rtol_ladder(bool quick);

/// Marks the Pareto front: stable runs that no other stable run beats in both error (all
/// nodes) and cost.
void mark_pareto(std::vector<StudyRow>& rows);

StudyResult run_study(const Scene& scene, const StudyOptions& options, std::ostream* progress = nullptr);

/// study.csv (one row per run, the front marked) and study_plot.tex (pgfplots, log-log error
/// against cost, the front drawn); returns the plot's PNG path when LaTeX and pdftoppm are
/// installed, else an empty path and `note` says why. Nothing is left half-written.
std::filesystem::path write_study(const StudyResult& result, const std::filesystem::path& dir, std::string& note);

std::string format_study(const StudyResult& result);

} // namespace vtb::harness
