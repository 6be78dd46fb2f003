#include "vtb/reproduction/paper_data.hh"
#include "vtb/problem/solver_names.hh"

#include "paper_data_parts.hh"

#include "vtb/base/input_error.hh"
#include "vtb/harness/tex.hh"
#include "vtb/problem/output.hh"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace vtb::reproduction {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables
namespace paper {

void Out::macro(const std::string& name, const std::string& value) {
  macros += tex_macro(name, value);
}
void Out::number(const std::string& name, double value, int digits) {
  macro(name, tex_number(value, digits));
}
void Out::number_and_raw(const std::string& name, double value, int digits) {
  number(name, value, digits);
  macro(name + "Raw", plain_number(value));
}

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!(x[i] > 0 && y[i] > 0)) continue;
    const double a = std::log(x[i]), b = std::log(y[i]);
    n += 1;
    sx += a;
    sy += b;
    sxx += a * a;
    sxy += a * b;
  }
  const double den = n * sxx - sx * sx;
  return n >= 2 && den > 0 ? (n * sxy - sx * sy) / den : std::nan("");
}

namespace {

std::string yes_no(const std::string& s) {
  return s == "true" ? "yes" : "\\textbf{no}";
}

/// The row of the timing table for (nodes, forces, solver); InputError if absent.
std::size_t timing_row(const CsvTable& t, int nodes, int forces, const std::string& solver) {
  for (std::size_t r = 0; r < t.rows(); ++r)
    if (t.number(r, "nodes") == nodes && t.number(r, "forces") == forces && t.text(r, "solver") == solver) return r;
  throw InputError("timing_table.csv: no row for " + std::to_string(nodes) + " nodes, " + std::to_string(forces) +
                   " forces, solver " + solver);
}

} // namespace

void timing(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "timing_table.csv");
  std::ostringstream rows, calibration;
  std::string last_case;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const std::string& label = t.text(r, "case");
    const bool first = label != last_case;
    if (first && r > 0) rows << "\\midrule\n";
    last_case = label;
    rows << (first ? tex_escape(label) + " (" + tex_number(t.number(r, "paper_fps_piii450")) + " frames/s)" : "")
         << " & \\texttt{" << tex_escape(t.text(r, "solver")) << "} & " << tex_number(t.number(r, "dt")) << " & "
         << yes_no(t.text(r, "stable")) << " & " << tex_number(t.number(r, "step_median_us")) << " & "
         << tex_number(t.number(r, "steps_per_second")) << " & " << tex_number(t.number(r, "precompute_ms")) << " & "
         << tex_number(t.number(r, "realtime_factor")) << (t.text(r, "timing_only") == "true" ? "$^*$" : "") << " & "
         << tex_number(t.number(r, "displacement_error_vs_fem")) << " \\\\\n";
    if (t.text(r, "solver") == solvers::kCvode)
      calibration << tex_escape(label) << " & " << tex_number(t.number(r, "nodes")) << " & "
                  << tex_number(t.number(r, "displacement_error_vs_fem")) << " \\\\\n";
  }
  out.files.emplace_back("timing_rows.tex", rows.str());
  out.files.emplace_back("calibration_rows.tex", calibration.str());

  // The numbers the text states: the 517-node plate under one force, and the 123-node one.
  const auto at = [&](int nodes, int forces, const std::string& solver, const std::string& col) {
    return t.number(timing_row(t, nodes, forces, solver), col);
  };
  const double full = at(517, 1, solvers::kFilteredFull, "step_median_us"),
               ie = at(517, 1, solvers::kImplicitEuler, "step_median_us");
  out.number("vtbFullStepUs", full);
  out.number("vtbIEStepUs", ie);
  out.number("vtbCvodeStepUs", at(517, 1, solvers::kCvode, "step_median_us"));
  out.number("vtbFemStepUs", at(517, 1, solvers::kFem, "step_median_us"));
  out.number("vtbSpeedupIE", ie / full, 2);
  out.number("vtbFullRT", at(517, 1, solvers::kFilteredFull, "realtime_factor"));
  out.number("vtbFullErr", at(517, 1, solvers::kFilteredFull, "displacement_error_vs_fem"), 2);
  out.number("vtbIEErr", at(517, 1, solvers::kImplicitEuler, "displacement_error_vs_fem"), 2);
  out.number("vtbCvodeErr", at(517, 1, solvers::kCvode, "displacement_error_vs_fem"), 2);
  out.number("vtbFourFullErr", at(517, 4, solvers::kFilteredFull, "displacement_error_vs_fem"), 2);
  out.number("vtbFourCvodeErr", at(517, 4, solvers::kCvode, "displacement_error_vs_fem"), 2);
  out.number("vtbPaperFpsLarge", at(517, 1, solvers::kFilteredFull, "paper_fps_piii450"));
  out.number("vtbPaperFpsSmall", at(123, 1, solvers::kFilteredFull, "paper_fps_piii450"));
  out.number("vtbFullFps", at(517, 1, solvers::kFilteredFull, "steps_per_second"));
  out.number("vtbFpsRatio",
             at(517, 1, solvers::kFilteredFull, "steps_per_second") /
                 at(517, 1, solvers::kFilteredFull, "paper_fps_piii450"),
             2);
  out.number("vtbSmallFullStepUs", at(123, 1, solvers::kFilteredFull, "step_median_us"));
  // The timing's spread: each step time is the median of several timed runs after a warm-up
  // (timing_repeats); the largest max/min ratio of those runs over the table's rows. A
  // reproduction made before the repetitions has none: one run, no spread to state.
  double spread = 1;
  int repeats = 1;
  if (t.has_column("timing_repeats"))
    for (std::size_t r = 0; r < t.rows(); ++r) {
      if (t.number(r, "timing_repeats") < 2 || !(t.number(r, "step_min_us") > 0)) continue;
      repeats = std::max(repeats, static_cast<int>(t.number(r, "timing_repeats")));
      spread = std::max(spread, t.number(r, "step_max_us") / t.number(r, "step_min_us"));
    }
  out.number("vtbTimingRepeats", repeats);
  out.number("vtbTimingSpread", spread, 3);
  out.macro("vtbNbStable",
            t.text(timing_row(t, 517, 1, solvers::kFilteredNeighbors), "stable") == "true" ? "stable" : "unstable");
}

void fidelity(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "fidelity.csv");
  // One row per case, in the CSV's order: P1 on the mesh against the continuum, then each
  // calibration against the continuum, and the fitted springs against P1 (what they are fitted
  // to), in percent.
  std::map<std::string, std::map<std::string, double>> error, against_p1;
  std::map<std::string, double> nodes, mesh_fem;
  std::vector<std::string> cases;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const std::string& c = t.text(r, "case");
    if (!nodes.count(c)) cases.push_back(c);
    nodes[c] = t.number(r, "nodes");
    mesh_fem[c] = 100 * t.number(r, "mesh_fem_continuum_error");
    error[c][t.text(r, "springs")] = 100 * t.number(r, "continuum_error");
    against_p1[c][t.text(r, "springs")] = 100 * t.number(r, "displacement_error");
  }
  std::ostringstream rows;
  double lloyd_worst = 0, fitted_worst = 0, fitted_worst_continuum = 0, mesh_worst = 0;
  int fitted_closer = 0, locking = 0; // cases where P1 misses by more than 5 %, and where the fit is closer
  for (const auto& c : cases) {
    auto& e = error[c];
    rows << tex_escape(c) << " & " << tex_number(nodes[c]) << " & " << tex_number(mesh_fem[c], 2) << " & "
         << tex_number(e["lloyd"], 2) << " & " << tex_number(e["van-gelder"], 2) << " & " << tex_number(e["fitted"], 2)
         << " & " << tex_number(against_p1[c]["fitted"], 2) << " \\\\\n";
    lloyd_worst = std::max(lloyd_worst, e["lloyd"]);
    fitted_worst = std::max(fitted_worst, against_p1[c]["fitted"]);
    fitted_worst_continuum = std::max(fitted_worst_continuum, e["fitted"]);
    mesh_worst = std::max(mesh_worst, mesh_fem[c]);
    if (mesh_fem[c] > 5) {
      ++locking;
      if (e["fitted"] < mesh_fem[c]) ++fitted_closer;
    }
  }
  out.files.emplace_back("fidelity_rows.tex", rows.str());
  out.number("vtbLloydWorst", lloyd_worst, 2);
  out.number("vtbFittedWorst", fitted_worst, 2);
  out.number("vtbFittedWorstContinuum", fitted_worst_continuum, 2);
  out.number("vtbMeshFemWorst", mesh_worst, 2);
  out.number("vtbLockingCases", locking);
  out.number("vtbFittedCloserCases", fitted_closer);
}

/// The fit's cost against nodes (spring_fit.csv): one sentence with each slab's nodes and
/// seconds in the CSV's order, and the held-out error on the largest; none where the build had
/// no CGAL meshers to make the slabs.
void fit_cost(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "spring_fit.csv");
  if (t.rows() == 0) {
    out.macro("vtbFitCost", "");
    return;
  }
  std::size_t largest = 0;
  std::string ladder;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    if (t.number(r, "nodes") > t.number(largest, "nodes")) largest = r;
    ladder += (r == 0              ? ""
               : r + 1 == t.rows() ? " and "
                                   : ", ") +
              tex_number(t.number(r, "fit_seconds"), 2) + "~s at " + tex_number(t.number(r, "nodes")) + " nodes";
  }
  out.macro("vtbFitCost", "Without its cache the fit of a clamped 3D CGAL slab took " + ladder +
                              " here (held-out error " + tex_number(100 * t.number(largest, "validation_error"), 2) +
                              "\\,\\% at " + tex_number(t.number(largest, "nodes")) + " nodes).");
}

void transient(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "transient.csv");
  // One row per dt: the tip error (percent of the peak) and the step (us) of each solver.
  std::map<double, std::map<std::string, std::pair<double, double>>> by_dt;
  for (std::size_t r = 0; r < t.rows(); ++r)
    by_dt[t.number(r, "dt")][t.text(r, "solver")] = {100 * t.number(r, "tip_error"), t.number(r, "step_median_us")};
  std::ostringstream rows;
  for (auto& [dt, s] : by_dt) {
    rows << tex_number(1000 * dt);
    for (const char* solver : {solvers::kFilteredFull, solvers::kFilteredTensor, solvers::kImplicitEuler})
      rows << " & " << tex_number(s[solver].first, 2);
    for (const char* solver : {solvers::kFilteredFull, solvers::kFilteredTensor, solvers::kImplicitEuler})
      rows << " & " << tex_number(s[solver].second, 2);
    rows << " \\\\\n";
  }
  out.files.emplace_back("transient_rows.tex", rows.str());
}

void fig3(const std::filesystem::path& dir, Out& out) {
  // Three times per model, from the file names the reproduction writes (SOLVER_tT.csv).
  std::map<std::string, std::vector<std::pair<double, std::string>>> snaps;
  for (const auto& e : std::filesystem::directory_iterator(dir / "fig3")) {
    const std::string f = e.path().filename().string();
    const auto u = f.rfind("_t");
    if (e.path().extension() != ".csv" || f.find("_cells") != std::string::npos || u == std::string::npos) continue;
    snaps[f.substr(0, u)].emplace_back(std::stod(f.substr(u + 2)), e.path().stem().string());
  }
  for (const char* model : {solvers::kFilteredFull, solvers::kFem})
    if (snaps[model].size() != 3) throw InputError((dir / "fig3").string() + ": needs three snapshots of " + model);
  // One magnification for all panels: the largest displacement drawn as 15 % of the plate's
  // length, rounded down to 1, 2 or 5 times a power of ten.
  double umax = 0, extent = 0;
  std::map<std::string, CsvTable> nodes;
  for (auto& [model, list] : snaps) {
    std::sort(list.begin(), list.end());
    for (const auto& [t, stem] : list) {
      nodes.emplace(stem, CsvTable::read(dir / "fig3" / (stem + ".csv")));
      const CsvTable& n = nodes.at(stem);
      for (std::size_t r = 0; r < n.rows(); ++r) {
        umax = std::max(umax, std::hypot(n.number(r, "ux"), n.number(r, "uy")));
        extent = std::max(extent, n.number(r, "x"));
      }
    }
  }
  const double raw = umax > 0 ? 0.15 * extent / umax : 1.0, p = std::pow(10.0, std::floor(std::log10(raw)));
  const double scale = raw >= 5 * p ? 5 * p : raw >= 2 * p ? 2 * p : p;
  out.number("vtbFigThreeScale", scale);
  double smax = 0;
  for (const auto& [model, list] : snaps)
    for (std::size_t k = 0; k < list.size(); ++k) {
      const std::string& stem = list[k].second;
      const CsvTable& n = nodes.at(stem);
      const CsvTable c = CsvTable::read(dir / "fig3" / (stem + "_cells.csv"));
      std::ostringstream os;
      os << "x y c\n";
      for (std::size_t r = 0; r < c.rows(); ++r) {
        const double s = c.number(r, "max_principal_strain");
        smax = std::max(smax, s);
        for (const char* v : {"n0", "n1", "n2"}) {
          const auto i = static_cast<std::size_t>(c.number(r, v));
          os << n.number(i, "x") + scale * n.number(i, "ux") << ' ' << n.number(i, "y") + scale * n.number(i, "uy")
             << ' ' << s << '\n';
        }
      }
      out.files.emplace_back("fig3_" + model + "_" + std::to_string(k) + ".dat", os.str());
    }
  const auto& times = snaps[solvers::kFilteredFull];
  out.number("vtbFigThreeTa", times[0].first);
  out.number("vtbFigThreeTb", times[1].first);
  out.number("vtbFigThreeTc", times[2].first);
  out.number_and_raw("vtbFigThreeStrainMax", smax, 2);
}

} // namespace paper

std::vector<std::pair<std::string, std::string>> paper_data(const std::filesystem::path& dir) {
  paper::Out out;
  const CsvTable meta = CsvTable::read(dir / "meta.csv");
  std::map<std::string, std::string> m;
  for (std::size_t r = 0; r < meta.rows(); ++r) m[meta.text(r, "key")] = meta.text(r, "value");
  out.macro("vtbQuickNote", m["quick"] == "true"
                                ? "Quick reproduction (\\texttt{-{}-quick}): " + tex_escape(m["duration_s"]) +
                                      "~s of simulated time and short ladders."
                                : "Full reproduction: " + tex_escape(m["duration_s"]) + "~s of simulated time.");
  out.macro("vtbMachine", tex_escape(m["cpu"]) + ", " + tex_escape(m["cores"]) + " cores");
  paper::timing(dir, out);
  paper::fidelity(dir, out);
  paper::fit_cost(dir, out);
  paper::transient(dir, out);
  paper::fig3(dir, out);
  paper::accuracy(dir, out);
  paper::stability(dir, out);
  paper::creep_scaling(dir, out);
  paper::haptics(dir, out);
  paper::multirate(dir, out);
  paper::tip_force(dir, out);
  paper::deep_press(dir, out);
  out.files.emplace_back("numbers.tex", out.macros);
  out.files.emplace_back("plot_styles.tex", std::string(plot_styles())); // the figures' look (paper/preamble.tex)
  return out.files;
}

void write_paper_data(const std::filesystem::path& reproduce_dir, const std::filesystem::path& out_dir) {
  auto files = paper_data(reproduce_dir);
  write_files_atomically(out_dir, files);
}

} // namespace vtb::reproduction
