#include "bindings.hh"

#include "vtb/base/input_error.hh"
#include "vtb/harness/compare.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/harness/study.hh"
#include "vtb/harness/sweep.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <functional>
#include <iostream>
#include <optional>
#include <variant>

namespace vtb::python {

namespace {

/// A table built column by column: numbers become float64 arrays, text a list of str (numpy
/// would fix a width), in the order the columns were added (the CSV's order where a CSV has them).
class Columns {
public:
  template <class Row>
  void number(const std::string& name, const std::vector<Row>& rows, const std::function<double(const Row&)>& f) {
    py::array_t<double> a(static_cast<py::ssize_t>(rows.size()));
    auto w = a.mutable_unchecked<1>();
    for (std::size_t k = 0; k < rows.size(); ++k) w(static_cast<py::ssize_t>(k)) = f(rows[k]);
    m_dict[py::str(name)] = a;
  }
  template <class Row>
  void text(const std::string& name, const std::vector<Row>& rows, const std::function<std::string(const Row&)>& f) {
    py::list l;
    for (const auto& r : rows) l.append(f(r));
    m_dict[py::str(name)] = l;
  }
  py::dict dict() const { return m_dict; }

private:
  py::dict m_dict;
};

py::array_t<double> column(const std::vector<double>& x) {
  return py::array_t<double>(static_cast<py::ssize_t>(x.size()), x.data());
}

py::array_t<double> rows3(const std::vector<std::array<double, 3>>& x) {
  py::array_t<double> a({static_cast<py::ssize_t>(x.size()), py::ssize_t(3)});
  auto w = a.mutable_unchecked<2>();
  for (std::size_t k = 0; k < x.size(); ++k)
    for (int d = 0; d < 3; ++d) w(static_cast<py::ssize_t>(k), d) = x[k][static_cast<std::size_t>(d)];
  return a;
}

py::list names(const std::vector<std::string>& x) {
  py::list l;
  for (const auto& s : x) l.append(s);
  return l;
}

/// `vtb run`'s tables: probes {t, probe, u (rows, 3)}, reactions {t, region, f (rows, 3)},
/// and summary.json's text.
py::dict tables_dict(const RunTables& t) {
  py::dict probes, reactions, out;
  probes["t"] = column(t.probe_t);
  probes["probe"] = names(t.probe_name);
  probes["u"] = rows3(t.probe_u);
  reactions["t"] = column(t.reaction_t);
  reactions["region"] = names(t.region);
  reactions["f"] = rows3(t.reaction_f);
  out["probes"] = probes;
  out["reactions"] = reactions;
  out["summary_json"] = t.summary_json;
  return out;
}

py::dict compare_dict(const harness::CompareResult& r) {
  using Row = harness::CompareRow;
  Columns c;
  c.text<Row>("solver", r.rows, [](const Row& x) { return x.solver; });
  c.number<Row>("dt", r.rows, [](const Row& x) { return x.report.dt; });
  c.number<Row>("steps", r.rows, [](const Row& x) { return static_cast<double>(x.report.steps_taken); });
  c.number<Row>("stable", r.rows, [](const Row& x) { return x.report.stable ? 1.0 : 0.0; });
  c.number<Row>("displacement_error_max", r.rows, [](const Row& x) { return x.error.displacement_max; });
  c.number<Row>("displacement_error_final", r.rows, [](const Row& x) { return x.error.displacement_final; });
  c.number<Row>("probe_error_max", r.rows, [](const Row& x) { return x.error.probe_max; });
  c.number<Row>("reaction_error_max", r.rows, [](const Row& x) { return x.error.reaction_max; });
  c.number<Row>("reaction_error_final", r.rows, [](const Row& x) { return x.error.reaction_final; });
  c.number<Row>("precompute_seconds", r.rows, [](const Row& x) { return x.report.precompute_seconds; });
  c.number<Row>("step_median_seconds", r.rows, [](const Row& x) { return x.report.step_seconds.median; });
  c.number<Row>("step_p99_seconds", r.rows, [](const Row& x) { return x.report.step_seconds.p99; });
  c.number<Row>("total_seconds", r.rows, [](const Row& x) { return x.wall_seconds; });
  c.number<Row>("displacement_error_away_max", r.rows, [](const Row& x) { return x.error.displacement_away_max; });
  using Dec = harness::DecompositionRow;
  Columns d;
  d.text<Dec>("run", r.decomposition, [](const Dec& x) { return x.a; });
  d.text<Dec>("against", r.decomposition, [](const Dec& x) { return x.b; });
  d.text<Dec>("meaning", r.decomposition, [](const Dec& x) { return x.meaning; });
  d.number<Dec>("displacement_error_max", r.decomposition, [](const Dec& x) { return x.error.displacement_max; });
  d.number<Dec>("displacement_error_final", r.decomposition, [](const Dec& x) { return x.error.displacement_final; });
  d.number<Dec>("reaction_error_max", r.decomposition, [](const Dec& x) { return x.error.reaction_max; });
  py::dict out;
  out["scene"] = r.scene;
  out["reference"] = r.reference;
  out["nodes"] = r.nodes;
  out["duration"] = r.duration;
  out["point_loads"] = names(r.point_loads);
  out["rows"] = c.dict();
  out["decomposition"] = d.dict();
  out["text"] = harness::format_compare(r);
  return out;
}

py::dict study_dict(const harness::StudyResult& r) {
  using Row = harness::StudyRow;
  Columns c;
  c.text<Row>("solver", r.rows, [](const Row& x) { return x.solver; });
  c.number<Row>("dt", r.rows, [](const Row& x) { return x.dt; });
  c.number<Row>("rtol", r.rows, [](const Row& x) { return x.rtol; });
  c.number<Row>("stable", r.rows, [](const Row& x) { return x.stable ? 1.0 : 0.0; });
  c.number<Row>("skipped", r.rows, [](const Row& x) { return x.skipped ? 1.0 : 0.0; });
  c.number<Row>("error_all", r.rows, [](const Row& x) { return x.error_all; });
  c.number<Row>("error_probes", r.rows, [](const Row& x) { return x.error_probes; });
  c.number<Row>("step_median_seconds", r.rows, [](const Row& x) { return x.step_median; });
  c.number<Row>("total_seconds", r.rows, [](const Row& x) { return x.total_seconds; });
  c.number<Row>("seconds_per_simulated_second", r.rows, [](const Row& x) { return x.cost; });
  c.number<Row>("pareto", r.rows, [](const Row& x) { return x.pareto ? 1.0 : 0.0; });
  c.text<Row>("note", r.rows, [](const Row& x) { return x.failure; });
  py::dict out;
  out["scene"] = r.scene;
  out["reference"] = r.reference;
  out["reference_note"] = r.reference_note;
  out["filter"] = r.filter;
  out["nodes"] = r.nodes;
  out["duration"] = r.duration;
  out["rows"] = c.dict();
  out["text"] = harness::format_study(r);
  return out;
}

py::dict sweep_dict(const std::vector<harness::SweepCell>& cells) {
  using Cell = harness::SweepCell;
  Columns c;
  c.text<Cell>("solver", cells, [](const Cell& x) { return x.solver; });
  c.number<Cell>("dt", cells, [](const Cell& x) { return x.dt; });
  c.number<Cell>("stiffness_scale", cells, [](const Cell& x) { return x.stiffness_scale; });
  c.number<Cell>("young_modulus", cells, [](const Cell& x) { return x.young_modulus; });
  c.number<Cell>("stable", cells, [](const Cell& x) { return x.stable ? 1.0 : 0.0; });
  c.text<Cell>("failure", cells, [](const Cell& x) { return x.failure; });
  c.number<Cell>("max_strain", cells, [](const Cell& x) { return x.max_strain; });
  c.number<Cell>("displacement_error_max", cells, [](const Cell& x) { return x.error; });
  c.number<Cell>("step_median_seconds", cells, [](const Cell& x) { return x.step_median; });
  c.number<Cell>("courant_dt", cells, [](const Cell& x) { return x.courant_dt; });
  py::dict out;
  out["rows"] = c.dict();
  out["criterion"] = harness::kStabilityCriterion;
  return out;
}

} // namespace

void bind_harness(py::module_& m) {
  m.def(
      "_run",
      [](const py::object& scene, std::optional<std::string> solver, std::optional<double> dt,
         std::optional<double> duration, const std::filesystem::path& out, bool frames) {
        harness::RunOverrides ov{solver, dt, duration, std::nullopt};
        const Scene s = harness::with_overrides(to_scene(scene), ov);
        RunTables t;
        {
          py::gil_scoped_release release;
          t = harness::run(s, out, frames);
        }
        return tables_dict(t);
      },
      py::arg("scene"), py::arg("solver") = py::none(), py::arg("dt") = py::none(), py::arg("duration") = py::none(),
      py::arg("out") = std::filesystem::path(), py::arg("frames") = false);
  m.def(
      "_compare",
      [](const py::object& scene, const std::vector<std::string>& solvers_, const std::string& reference, double dt,
         const std::filesystem::path& out) {
        const Scene s = to_scene(scene);
        if (dt != 0) checked_dt(dt); // 0: the scene's
        harness::CompareResult r;
        {
          py::gil_scoped_release release;
          r = harness::run_compare(s, solvers_, reference, dt, nullptr, {out, false});
          if (!out.empty()) harness::write_compare(r, out);
        }
        return compare_dict(r);
      },
      py::arg("scene"), py::arg("solvers"), py::arg("reference") = solvers::kFem, py::arg("dt") = 0.0,
      py::arg("out") = std::filesystem::path());
  m.def(
      "_study",
      [](const py::object& scene, const std::vector<std::string>& solvers_, const std::string& reference, bool quick,
         const std::filesystem::path& out, bool verbose) {
        const Scene s = to_scene(scene);
        harness::StudyOptions o;
        o.solvers = solvers_;
        o.reference = reference;
        o.quick = quick;
        harness::StudyResult r;
        {
          py::gil_scoped_release release;
          r = harness::run_study(s, o, verbose ? &std::cerr : nullptr);
          std::string note;
          if (!out.empty()) harness::write_study(r, out, note);
        }
        return study_dict(r);
      },
      py::arg("scene"), py::arg("solvers") = std::vector<std::string>{}, py::arg("reference") = solvers::kFem,
      py::arg("quick") = false, py::arg("out") = std::filesystem::path(), py::arg("verbose") = false);
  m.def(
      "_sweep",
      [](const py::object& scene, const std::vector<double>& dts, const std::vector<double>& scales,
         std::optional<std::vector<std::string>> solvers_, const std::filesystem::path& out) {
        const Scene s = to_scene(scene);
        const auto names_ = solvers_ ? *solvers_ : harness::default_sweep_solvers();
        std::vector<harness::SweepCell> cells;
        {
          py::gil_scoped_release release;
          cells = harness::run_sweep(s, dts, scales, names_, nullptr, false);
          if (!out.empty()) harness::write_sweep(cells, out / "stability.csv");
        }
        return sweep_dict(cells);
      },
      py::arg("scene"), py::arg("dt"), py::arg("stiffness_scale") = std::vector<double>{1.0},
      py::arg("solvers") = py::none(), py::arg("out") = std::filesystem::path());
  m.def(
      "solvers", [] { return solvers::names(); }, "Every solver name of the registry");
  m.def(
      "interactive_solvers", [] { return solvers::names(solvers::is_stepper); },
      "The solvers a vtb.Simulation steps (the fixed-step spring solvers)");
}

} // namespace vtb::python
