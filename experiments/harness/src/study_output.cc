#include "study_json.hh"
#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"
#include "vtb/harness/study.hh"
#include "vtb/harness/tex.hh"
#include "vtb/problem/solver_names.hh"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

// vtb study's outputs: study.csv, study.json and the plot; merging the parts of a sharded study.
namespace vtb::harness {

/// A row as one line of text, every double exact (hexadecimal), for the gather on rank 0 and
/// study.json.
nlohmann::json row_json(const StudyRow& r) {
  const auto hex = [](double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%a", x);
    return std::string(b);
  };
  return {{"cell", r.cell},
          {"solver", r.solver},
          {"dt", hex(r.dt)},
          {"rtol", hex(r.rtol)},
          {"stable", r.stable},
          {"skipped", r.skipped},
          {"failure", r.failure},
          {"error_all", hex(r.error_all)},
          {"error_probes", hex(r.error_probes)},
          {"step_median", hex(r.step_median)},
          {"total_seconds", hex(r.total_seconds)},
          {"cost", hex(r.cost)},
          {"binding", r.binding}};
}

StudyRow row_from_json(const nlohmann::json& j) {
  const auto num = [&](const char* key) { return std::strtod(j.at(key).get<std::string>().c_str(), nullptr); };
  StudyRow r;
  r.cell = j.at("cell").get<long>();
  r.solver = j.at("solver").get<std::string>();
  r.dt = num("dt");
  r.rtol = num("rtol");
  r.stable = j.at("stable").get<bool>();
  r.skipped = j.at("skipped").get<bool>();
  r.failure = j.at("failure").get<std::string>();
  r.error_all = num("error_all");
  r.error_probes = num("error_probes");
  r.step_median = num("step_median");
  r.total_seconds = num("total_seconds");
  r.cost = num("cost");
  r.binding = j.at("binding").get<std::string>();
  return r;
}

namespace {

std::string num(double x) {
  if (!std::isfinite(x)) return "";
  std::ostringstream os;
  os << std::setprecision(8) << x;
  return os.str();
}

/// The solvers a study's rows plot, in the order they ran (`filtered` as the scene's filter).
std::vector<std::string> plotted_solvers(const StudyResult& r) {
  std::vector<std::string> names;
  for (const auto& row : r.rows) {
    const std::string name = row.solver == solvers::kFiltered ? "filtered-" + r.filter : row.solver;
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

/// The figure's series, in the format of the reproduction's (paper_series.cc): data/acc_NAME.dat
/// per solver the study ran (cost error; empty when it had no stable run), data/pareto.dat, and
/// data/numbers.tex naming the reference.
std::vector<std::pair<std::string, std::string>> plot_data(const StudyResult& r) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const std::string& name : plotted_solvers(r)) {
    std::ostringstream t;
    t << "cost error\n";
    for (const auto& row : r.rows)
      if ((row.solver == solvers::kFiltered ? "filtered-" + r.filter : row.solver) == name && row.stable &&
          std::isfinite(row.error_all) && row.error_all > 0)
        t << num(row.cost) << ' ' << num(row.error_all) << '\n';
    files.emplace_back("acc_" + name + ".dat", t.str());
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

/// Each solver's pgfplots style (plot_styles.tex, shared with the paper's figures): cvode,
/// fem and explicit have styles of their own names.
std::string plot_style(const std::string& solver) {
  static constexpr std::pair<const char*, const char*> kStyles[] = {{solvers::kFilteredFull, "full"},
                                                                    {solvers::kFilteredNeighbors, "neighbors"},
                                                                    {solvers::kFilteredTensor, "tensor"},
                                                                    {solvers::kFilteredMultigrid, "multigrid"},
                                                                    {solvers::kFilteredTensorMultigrid, "tensormg"},
                                                                    {solvers::kImplicitEuler, "ie"},
                                                                    {solvers::kBullet, "bullet"},
                                                                    {solvers::kCvode, solvers::kCvode},
                                                                    {solvers::kFem, solvers::kFem},
                                                                    {solvers::kExplicit, solvers::kExplicit}};
  for (const auto& [name, style] : kStyles)
    if (solver == name) return style;
  return "black, mark=+";
}

/// study_plot.tex: the paper's accuracy-against-cost figure (paper/figures/accuracy_speed.tex)
/// for the solvers this study ran, whichever they are, drawn from data/ (standalone class) in
/// vtb's figure look (plot_styles.tex beside it). Legend entries are drawn apart from the data,
/// so that an empty series cannot shift them.
std::string plot_tex(const std::vector<std::string>& names) {
  std::ostringstream t;
  t << "\\documentclass[border=4pt]{standalone}\n\\input{plot_styles.tex}\n\\input{data/numbers.tex}\n"
    << "\\begin{document}\n\\begin{tikzpicture}\n"
    << "\\begin{axis}[vtb, width=9cm, height=6.2cm, xmode=log, ymode=log,\n"
    << "  xlabel={wall time per simulated second [s]}, ylabel={max.\\ rel.\\ $L_2$ displacement error vs "
       "\\vtbAccuracyReference},\n  legend pos=outer north east]\n";
  for (const std::string& s : names)
    t << "\\addlegendimage{" << plot_style(s) << "} \\addlegendentry{" << tex_escape(s) << "}\n";
  t << "\\addlegendimage{black, thick, dashed, mark=o, mark size=3.5pt} \\addlegendentry{Pareto front}\n";
  for (const std::string& s : names)
    t << "\\addplot[" << plot_style(s) << ", forget plot] table[x=cost, y=error] {data/acc_" << s << ".dat};\n";
  t << "\\addplot[black, thick, dashed, mark=o, mark size=3.5pt, forget plot] table[x=cost, y=error] "
       "{data/pareto.dat};\n\\end{axis}\n\\end{tikzpicture}\n\\end{document}\n";
  return t.str();
}

} // namespace

namespace {

/// The whole result, for vtb merge: what the study was and every row exact.
nlohmann::json study_json(const StudyResult& r) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& row : r.rows) rows.push_back(row_json(row));
  return {{"scene", r.scene},
          {"reference", r.reference},
          {"reference_note", r.reference_note},
          {"filter", r.filter},
          {"nodes", r.nodes},
          {"duration", r.duration},
          {"cells", r.cells},
          {"shard", r.shard.index},
          {"shards", r.shard.count},
          {"timing_shared", r.timing_shared},
          {"rows", rows}};
}

} // namespace

StudyResult merge_studies(const std::vector<std::filesystem::path>& dirs) {
  if (dirs.empty()) throw InputError("vtb merge: no part folders given");
  StudyResult all;
  std::vector<int> seen;
  for (const auto& dir : dirs) {
    const auto file = dir / "study.json";
    std::ifstream in(file);
    if (!in)
      throw InputError(file.string() + ": cannot be read (is " + dir.string() + " a part of vtb study --shard?)");
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
      throw InputError(file.string() + ": not a study.json (" + e.what() + ")");
    }
    const auto what = [&](const char* key) { return j.at(key).dump(); };
    if (seen.empty()) {
      all.scene = j.at("scene").get<std::string>();
      all.reference = j.at("reference").get<std::string>();
      all.reference_note = j.at("reference_note").get<std::string>();
      all.filter = j.at("filter").get<std::string>();
      all.nodes = j.at("nodes").get<int>();
      all.duration = j.at("duration").get<double>();
      all.cells = j.at("cells").get<long>();
      all.shard.count = j.at("shards").get<int>();
      seen.assign(static_cast<std::size_t>(all.shard.count), 0);
    } else {
      for (const char* key : {"scene", "reference", "filter", "nodes", "cells", "shards"})
        if (what(key) != study_json(all).at(key).dump())
          throw InputError(file.string() + ": a part of another study (" + key + " is " + what(key) + ", not " +
                           study_json(all).at(key).dump() + ")");
    }
    const int k = j.at("shard").get<int>();
    if (k < 0 || k >= all.shard.count || seen[static_cast<std::size_t>(k)]++)
      throw InputError(file.string() + ": part " + std::to_string(k) + " of " + std::to_string(all.shard.count) +
                       " is given twice");
    all.timing_shared = all.timing_shared || j.at("timing_shared").get<bool>();
    for (const auto& row : j.at("rows")) all.rows.push_back(row_from_json(row));
  }
  for (std::size_t k = 0; k < seen.size(); ++k)
    if (!seen[k])
      throw InputError("vtb merge: part " + std::to_string(k) + " of " + std::to_string(seen.size()) +
                       " is missing (run vtb study --shard " + std::to_string(k) + "/" + std::to_string(seen.size()) +
                       ")");
  std::sort(all.rows.begin(), all.rows.end(), [](const StudyRow& a, const StudyRow& b) { return a.cell < b.cell; });
  for (auto& r : all.rows) r.pareto = false;
  mark_pareto(all.rows);
  all.shard = Shard{};
  return all;
}

std::filesystem::path write_study(const StudyResult& r, const std::filesystem::path& dir, std::string& note) {
  ensure_directory(dir);
  std::ostringstream c;
  c << "solver,dt,rtol,stable,error_all,error_probes,step_median_seconds,total_seconds,seconds_per_simulated_second,"
       "realtime_factor,pareto,note,binding\n";
  for (const auto& row : r.rows)
    c << row.solver << ',' << num(row.dt) << ',' << (row.rtol > 0 ? num(row.rtol) : "") << ','
      << (row.skipped  ? ""
          : row.stable ? "true"
                       : "false")
      << ',' << num(row.error_all) << ',' << num(row.error_probes) << ',' << (row.skipped ? "" : num(row.step_median))
      << ',' << (row.skipped ? "" : num(row.total_seconds)) << ',' << (row.skipped ? "" : num(row.cost)) << ','
      << (row.stable ? num(1.0 / row.cost) : "") << ',' << (row.pareto ? "true" : "false") << ",\"" << row.failure
      << "\",\"" << row.binding << "\"\n";
  write_files_atomically(dir / "data", plot_data(r));
  write_files_atomically(dir, {{"study.csv", c.str()},
                               {"study.json", study_json(r).dump(1) + "\n"},
                               {"plot_styles.tex", std::string(plot_styles())},
                               {"study_plot.tex", plot_tex(plotted_solvers(r))}});
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
