#pragma once
/// \file
/// `vtb study SCENE`: accuracy against cost on any scene. Every fixed-step solver over a dt
/// ladder, CVODE over an rtol ladder, each measured against one converged reference run, and
/// the Pareto front of error against wall time per simulated second.
///
/// A study is a list of cells (one solver at one step or tolerance). Under `mpirun -np N` the
/// ranks take cells from one queue (costliest first) while rank 0 first runs the reference and
/// sends it to the others, which keep their finished runs until it arrives; rank 0 gathers the
/// rows, in the serial order. With `--shard K/N` a process runs the K-th of N static parts
/// (split by estimated cost; each part runs the reference itself) and `vtb merge` joins the
/// parts' study.json files. Errors are the serial run's to the bit; timing columns are not.

#include "vtb/harness/ranks.hh"
#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"
#include "vtb/problem/scene.hh"
#include "vtb/problem/solver_names.hh"

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace vtb::harness {

struct StudyOptions {
  std::vector<std::string> solvers; ///< empty: default_study_solvers(the scene's dimension)
  Shard shard;                      ///< --shard K/N: only the K-th of N parts
  /// fem: the continuum (P2 at the static ladder's level, at fem_reference_step's step);
  /// cvode: the spring model's exact trajectory (rtol 1e-10)
  std::string reference = solvers::kFem;
  bool quick = false; ///< shorter ladders
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
  long cell = 0;       ///< its place in the serial study
  std::string binding; ///< where it ran (ranks.hh binding()): a timing column
};

struct StudyResult {
  std::string scene, reference;
  std::string filter = solvers::kFilterFull; ///< the filter `filtered` ran (the scene's, auto resolved)
  int nodes = 0;
  double duration = 0;
  std::string reference_note; ///< what the reference run was
  std::vector<StudyRow> rows;
  long cells = 0;             ///< in the whole study (a shard holds some of them)
  Shard shard;                ///< which part this is (1 part: the whole study)
  bool timing_shared = false; ///< two ranks of one node may have shared a core: step times may be each other's
};

/// What a study runs when no solvers are named: every filter of the registry that suits a
/// body of this dimension (the V-cycle filter is for 3D meshes), implicit Euler, explicit and
/// CVODE, so that a study answers "which is best on my scene" without the user knowing names.
std::vector<std::string> default_study_solvers(int dim);

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

/// Runs the study (this rank's or this shard's share of it). Under MPI every rank calls it and
/// rank 0 gets the whole result; the others get their own rows only and write nothing.
StudyResult run_study(const Scene& scene, const StudyOptions& options, std::ostream* progress = nullptr);

/// The FEM reference converged in time: P2 on the scene's mesh refined `refinements` times (the
/// static ladder's level), run at 4 dt, 2 dt and dt (dt the scene's). The differences of
/// successive runs, on compare()'s measure (the largest relative L2 over all nodes, the scale of
/// a study row's error), fall as h^p: their ratio gives the observed order p (clamped to [1, 2]:
/// generalized-alpha is second order, first order in a transient started by a step load, whose
/// start is inconsistent) and the error at dt, d(dt) / (2^p - 1). Within `tolerance` the run at
/// dt is `out`; else it runs again at dt / 2 or dt / 4, the first whose error (2^-p per halving)
/// is within, dt / 4 at most. The estimate is the reference's own: P1 on the mesh as a proxy,
/// assuming order 2, missed it 2.3x low on a strip two cells thick under a step load. Cost: 1.75
/// runs at dt where dt suffices. `log` gets a line per run and its progress; `distributed` runs
/// each over the MPI ranks.
struct ReferenceStep {
  double dt = 0;    ///< the kept run's step
  double error = 0; ///< its estimated time error (relative)
  double order = 2; ///< the observed order of the time error, in [1, 2]
  std::string how;  ///< e.g. "time error at dt ~0.5 % (P2 at 4 dt, 2 dt and dt: order 1.3; allowed 1 %)"
};
template <int dim>
ReferenceStep fem_reference_in_time(const Scene& scene, const Problem<dim>& problem, int refinements, double tolerance,
                                    Trajectory<dim>& out, std::ostream* log = nullptr, bool distributed = false);

/// Joins the parts of a sharded study (each part's study.json) into the whole: InputError
/// naming the folder when the parts are of different studies, or a part is missing or twice.
StudyResult merge_studies(const std::vector<std::filesystem::path>& part_dirs);

/// study.csv (one row per run, the front marked), study.json (the rows whole, for vtb merge) and study_plot.tex
/// (pgfplots, log-log error against cost, the front drawn); returns the plot's PNG path when LaTeX and pdftoppm are
/// installed, else an empty path and `note` says why. Nothing is left half-written.
std::filesystem::path write_study(const StudyResult& result, const std::filesystem::path& dir, std::string& note);

std::string format_study(const StudyResult& result);

} // namespace vtb::harness
