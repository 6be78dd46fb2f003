#include "vtb/harness/study.hh"
#include "vtb/harness/tex.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/cvode_solver.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace vtb::harness {

std::vector<double> dt_ladder(double dt, bool quick) {
  if (quick) return {4 * dt, dt, dt / 4};
  return {4 * dt, 2 * dt, dt, dt / 2, dt / 4, dt / 8};
}

std::vector<double> rtol_ladder(bool quick) {
  if (quick) return {1e-3, 1e-5};
  return {1e-3, 1e-4, 1e-5, 1e-6, 1e-7};
}

void mark_pareto(std::vector<StudyRow>& rows) {
  for (auto& r : rows) {
    r.pareto = r.stable && std::isfinite(r.error_all);
    if (!r.pareto) continue;
    for (const auto& o : rows)
      if (&o != &r && o.stable && std::isfinite(o.error_all) && o.error_all <= r.error_all && o.cost <= r.cost &&
          (o.error_all < r.error_all || o.cost < r.cost)) {
        r.pareto = false;
        break;
      }
  }
}

namespace {

/// The reference, converged at its own step: the continuum (P2, one refinement, dt / 4), or the
/// spring model's exact trajectory (CVODE at rtol 1e-10). Returns what it was.
template <int dim>
std::string reference_run(const Scene& scene, const Model<dim>& model, const std::string& reference,
                          Trajectory<dim>& ref) {
  RunReport rr;
  std::string note;
  if (reference == solvers::kFem) {
    fem::FemOptions f = fem::options_from(scene.solver);
    f.degree = 2;
    f.refinements = 1;
    f.dt = scene.solver.dt / 4;
    f.static_solve = false;
    rr = fem::simulate<dim>(model, scene.material, f, ref, true);
    note = "fem, P2, 1 refinement, " + f.scheme + ", dt = " + std::to_string(f.dt) + " s";
  } else if (reference == solvers::kCvode) {
    rr = simulate_cvode(model, CvodeOptions{1e-10, 1e-14}, ref, true);
    note = "cvode, rtol 1e-10, atol 1e-14";
  } else {
    throw InputError("vtb study: --reference must be fem or cvode, not \"" + reference + "\"");
  }
  if (!rr.stable) throw std::runtime_error("vtb study: the reference run failed: " + rr.failure);
  return note;
}

/// A run's row: its cost and, when it stayed stable, its errors against the reference.
template <int dim>
StudyRow measured_row(StudyRow row, const RunReport& rep, const Trajectory<dim>& tr, const Trajectory<dim>& ref,
                      double wall, double duration) {
  row.stable = rep.stable;
  row.failure = rep.failure;
  row.step_median = rep.step_seconds.median;
  row.total_seconds = wall;
  row.cost = wall / duration;
  if (row.dt == 0) row.dt = rep.dt;
  if (rep.stable) {
    const ErrorMetrics e = compare(tr, ref);
    row.error_all = e.displacement_max;
    row.error_probes = e.probe_max;
  } else {
    row.error_all = row.error_probes = std::nan("");
  }
  return row;
}

/// A run too long to take (more steps than the budget): a row that says so.
StudyRow skipped_row(const std::string& solver, double dt, double steps, double budget) {
  StudyRow row;
  row.solver = solver;
  row.dt = dt;
  row.stable = false;
  row.skipped = true;
  row.error_all = row.error_probes = std::nan("");
  std::ostringstream why;
  why << "skipped: " << std::setprecision(3) << steps << " steps (more than " << budget << ")";
  row.failure = why.str();
  return row;
}

/// A fixed-step solver's ladder: the scene's dt ladder, or the explicit scheme's fractions of
/// its stability limit.
template <int dim>
std::vector<double> solver_dts(const Scene& scene, const Model<dim>& model, const std::string& solver, bool quick) {
  if (solver != solvers::kExplicit) return dt_ladder(scene.solver.dt, quick);
  const double tau = model.net.stiffness.size() ? model.net.damping[0] / model.net.stiffness[0] : 0.0;
  const double limit = explicit_critical_dt(max_omega_squared(model, false), tau, model.net.mass_damping);
  return quick ? std::vector<double>{0.9 * limit} : std::vector<double>{0.9 * limit, 0.45 * limit};
}

template <int dim>
StudyResult study_impl(const Scene& scene, const Model<dim>& model, const StudyOptions& o, std::ostream* log) {
  using clock = std::chrono::steady_clock;
  StudyResult res;
  res.scene = scene.name;
  res.reference = o.reference;
  res.filter = scene.solver.filter;
  res.nodes = model.num_nodes();
  res.duration = model.duration;
  Trajectory<dim> ref;
  res.reference_note = reference_run(scene, model, o.reference, ref);
  if (log) *log << "reference: " << res.reference_note << "\n";
  const auto add = [&](StudyRow row) {
    if (log)
      *log << "  " << row.solver << (row.rtol > 0 ? " rtol " : " dt ") << (row.rtol > 0 ? row.rtol : row.dt)
           << (row.skipped  ? " " + row.failure
               : row.stable ? ""
                            : " UNSTABLE")
           << (row.skipped
                   ? ""
                   : ": error " + std::to_string(row.error_all) + ", " + std::to_string(row.total_seconds) + " s")
           << "\n";
    res.rows.push_back(std::move(row));
  };
  for (const auto& solver : o.solvers) {
    if (solver == solvers::kCvode) {
      for (double rtol : rtol_ladder(o.quick)) {
        Trajectory<dim> tr;
        const auto a = clock::now();
        const RunReport rep = simulate_cvode(model, CvodeOptions{rtol, rtol * 1e-4}, tr, true);
        StudyRow row;
        row.solver = solver;
        row.rtol = rtol;
        add(measured_row(row, rep, tr, ref, std::chrono::duration<double>(clock::now() - a).count(), model.duration));
      }
      continue;
    }
    for (double dt : solver_dts(scene, model, solver, o.quick)) {
      const double steps = model.duration / dt, budget = o.quick ? 2e5 : 2e6;
      if (steps > budget) {
        add(skipped_row(solver, dt, steps, budget));
        continue;
      }
      Trajectory<dim> tr;
      const auto a = clock::now();
      const RunReport rep = run_solver(scene, model, solver, dt, tr);
      StudyRow row;
      row.solver = solver;
      row.dt = dt;
      add(measured_row(row, rep, tr, ref, std::chrono::duration<double>(clock::now() - a).count(), model.duration));
    }
  }
  mark_pareto(res.rows);
  return res;
}

std::string num(double x) {
  if (!std::isfinite(x)) return "";
  std::ostringstream os;
  os << std::setprecision(8) << x;
  return os.str();
}

/// The figure: pgfplots, log-log, every stable run a mark per solver, the front a line.
/// The study's series in the format of the reproduction's (paper_series.cc), so that the
/// paper's own Pareto figure, paper/figures/accuracy_speed.tex, draws both: data/acc_NAME.dat
/// per solver (cost error), data/pareto.dat, and data/numbers.tex naming the reference.
std::vector<std::pair<std::string, std::string>> plot_data(const StudyResult& r, const std::string& filter) {
  const auto plotted = [&](const std::string& solver) {
    return solver == solvers::kFiltered ? "filtered-" + filter : solver;
  };
  std::vector<std::pair<std::string, std::string>> files;
  for (const char* name : {solvers::kFilteredFull, solvers::kFilteredNeighbors, solvers::kImplicitEuler,
                           solvers::kCvode, solvers::kFem, solvers::kExplicit}) {
    std::ostringstream t;
    t << "cost error\n";
    for (const auto& row : r.rows)
      if (plotted(row.solver) == name && row.stable && std::isfinite(row.error_all) && row.error_all > 0)
        t << num(row.cost) << ' ' << num(row.error_all) << '\n';
    files.emplace_back(std::string("acc_") + name + ".dat", t.str());
  }
  std::vector<const StudyRow*> front;
  for (const auto& row : r.rows)
    if (row.pareto && row.error_all > 0) front.push_back(&row);
  std::sort(front.begin(), front.end(), [](const StudyRow* a, const StudyRow* b) { return a->cost < b->cost; });
  std::ostringstream p;
  p << "cost error\n";
  for (const auto* row : front) p << num(row->cost) << ' ' << num(row->error_all) << '\n';
  files.emplace_back("pareto.dat", p.str());
  files.emplace_back("numbers.tex",
                     tex_macro("vtbAccuracyReference", r.reference == solvers::kCvode ? "CVODE" : "FEM"));
  return files;
}

/// study_plot.tex: the paper's figure drawn alone from data/ (standalone class).
std::string plot_tex(const std::filesystem::path& paper_dir) {
  return "\\documentclass[border=4pt]{standalone}\n\\input{" + (paper_dir / "preamble.tex").string() +
         "}\n\\begin{document}\n\\input{" + (paper_dir / "figures/accuracy_speed.tex").string() +
         "}\n\\end{document}\n";
}

} // namespace

StudyResult run_study(const Scene& scene_in, const StudyOptions& o, std::ostream* log) {
  for (const auto& solver : o.solvers) // before any run: a typo costs nothing
    if (!solvers::find(solver, "vtb study").springs)
      throw InputError("vtb study: solver \"" + solver + "\" is not one to study (" +
                       solvers::list(solvers::is_spring) + ")");
  Scene scene = scene_in;
  if (o.quick && scene.duration > 1.0) { // a quick study looks at the first second
    scene.duration = 1.0;
    scene.output_interval = std::min(scene.output_interval, scene.duration);
  }
  return with_model(scene, [&](const auto& model) {
    constexpr int dim = std::decay_t<decltype(model)>::dimension;
    return study_impl<dim>(scene, model, o, log);
  });
}

std::filesystem::path write_study(const StudyResult& r, const std::filesystem::path& dir, std::string& note) {
  ensure_directory(dir);
  std::ostringstream c;
  c << "solver,dt,rtol,stable,error_all,error_probes,step_median_seconds,total_seconds,seconds_per_simulated_second,"
       "realtime_factor,pareto,note\n";
  for (const auto& row : r.rows)
    c << row.solver << ',' << num(row.dt) << ',' << (row.rtol > 0 ? num(row.rtol) : "") << ','
      << (row.skipped  ? ""
          : row.stable ? "true"
                       : "false")
      << ',' << num(row.error_all) << ',' << num(row.error_probes) << ',' << (row.skipped ? "" : num(row.step_median))
      << ',' << (row.skipped ? "" : num(row.total_seconds)) << ',' << (row.skipped ? "" : num(row.cost)) << ','
      << (row.stable ? num(1.0 / row.cost) : "") << ',' << (row.pareto ? "true" : "false") << ",\"" << row.failure
      << "\"\n";
  write_files_atomically(dir / "data", plot_data(r, r.filter));
  write_files_atomically(dir, {{"study.csv", c.str()}, {"study_plot.tex", plot_tex(VTB_PAPER_DIR)}});
  // The PNG needs LaTeX (pgfplots) and poppler: both optional here, so their absence is a note.
  if (std::system("command -v pdflatex >/dev/null 2>&1 && command -v pdftoppm >/dev/null 2>&1") != 0) {
    note = "no plot: pdflatex or pdftoppm is not installed (study_plot.tex is written; the paper's setup installs "
           "them)";
    return {};
  }
  const std::string d = dir.string();
  const std::string cmd =
      "cd '" + d +
      "' && pdflatex -interaction=batchmode -halt-on-error -no-shell-escape "
      "study_plot.tex >/dev/null 2>&1 && pdftoppm -png -r 150 -singlefile study_plot.pdf study_plot "
      ">/dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) {
    note = "no plot: pdflatex failed on study_plot.tex (see study_plot.log)";
    return {};
  }
  return dir / "study_plot.png";
}

std::string format_study(const StudyResult& r) {
  std::ostringstream os;
  char line[256];
  os << "study of " << r.scene << ": " << r.nodes << " nodes, " << r.duration << " s simulated; reference "
     << r.reference_note << "\n";
  std::snprintf(line, sizeof line, "%-20s %11s %8s %7s %12s %12s %12s %10s %7s\n", "solver", "dt [s]", "rtol", "stable",
                "error (all)", "error (prb)", "step [us]", "wall/sim", "pareto");
  os << line;
  for (const auto& row : r.rows) {
    char rtol[16] = "-";
    if (row.rtol > 0) std::snprintf(rtol, sizeof rtol, "%.0e", row.rtol);
    if (row.skipped) {
      std::snprintf(line, sizeof line, "%-20s %11.3g %8s  %s\n", row.solver.c_str(), row.dt, rtol, row.failure.c_str());
    } else {
      std::snprintf(line, sizeof line, "%-20s %11.3g %8s %7s %12.3e %12.3e %12.2f %10.4f %7s\n", row.solver.c_str(),
                    row.dt, rtol, row.stable ? "yes" : "NO", row.error_all, row.error_probes, row.step_median * 1e6,
                    row.cost, row.pareto ? "*" : "");
    }
    os << line;
  }
  os << "error: max over time of the relative L2 displacement error; wall/sim: wall seconds per simulated second; "
        "*: on the Pareto front\n";
  return os.str();
}

} // namespace vtb::harness
