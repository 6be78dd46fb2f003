// The plotted series of `paper_data`: accuracy against speed, convergence, decomposition,
// stability, creep, scaling, the haptic loop, the deep press.
#include "paper_data_parts.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/integrator.hh"

#include "vtb/harness/tex.hh"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

namespace vtb::reproduction::paper {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables

std::string series(const std::string& header, const std::vector<std::vector<double>>& columns) {
  std::ostringstream os;
  os.precision(8);
  os << header << '\n';
  for (std::size_t i = 0; !columns.empty() && i < columns[0].size(); ++i) {
    for (std::size_t c = 0; c < columns.size(); ++c) os << (c ? " " : "") << columns[c][i];
    os << '\n';
  }
  return os.str();
}

namespace {

/// The distinct values of a text column, in order of first appearance.
std::vector<std::string> distinct(const CsvTable& t, const std::string& name) {
  std::vector<std::string> v;
  for (std::size_t r = 0; r < t.rows(); ++r)
    if (std::find(v.begin(), v.end(), t.text(r, name)) == v.end()) v.push_back(t.text(r, name));
  return v;
}

double max_relative_deviation(const std::vector<double>& run, const std::vector<double>& ref) {
  double dev = 0, scale = 0;
  for (std::size_t i = 0; i < run.size() && i < ref.size(); ++i) {
    dev = std::max(dev, std::abs(run[i] - ref[i]));
    scale = std::max(scale, std::abs(ref[i]));
  }
  return scale > 0 ? dev / scale : std::nan("");
}

} // namespace

namespace {

/// One run on the accuracy-against-cost plane.
struct Point {
  double cost, error;
  std::string solver;
};

/// pareto.dat, and the numbers the caption states: the front's size and solvers, the lowest error.
void pareto(const std::vector<Point>& points, Out& out) {
  std::vector<Point> front;
  for (const Point& p : points) {
    const bool dominated = std::any_of(points.begin(), points.end(), [&](const Point& q) {
      return q.cost <= p.cost && q.error <= p.error && (q.cost < p.cost || q.error < p.error);
    });
    if (!dominated) front.push_back(p);
  }
  std::sort(front.begin(), front.end(), [](const Point& x, const Point& y) { return x.cost < y.cost; });
  std::vector<double> fc, fe;
  std::string names;
  for (const Point& p : front) {
    fc.push_back(p.cost);
    fe.push_back(p.error);
    if (names.find(p.solver) == std::string::npos) names += (names.empty() ? "" : ", ") + p.solver;
  }
  out.files.emplace_back("pareto.dat", series("cost error", {fc, fe}));
  out.number("vtbParetoCount", static_cast<double>(front.size()));
  out.macro("vtbParetoSolvers", "\\texttt{" + tex_escape(names) + "}");
  const auto best = std::min_element(points.begin(), points.end(), [](auto& x, auto& y) { return x.error < y.error; });
  if (best != points.end()) {
    out.number("vtbBestErr", best->error, 2);
    out.macro("vtbBestSolver", "\\texttt{" + tex_escape(best->solver) + "}");
  }
}

/// conv_*.dat (error against CVODE over dt, and CVODE over its rtol), the fitted orders, and
/// the spring model's own error for the decomposition figure.
void convergence(const std::filesystem::path& dir, const CsvTable& a, const std::function<bool(std::size_t)>& ok,
                 Out& out) {
  for (const auto& [s, file] : std::vector<std::pair<std::string, std::string>>{{solvers::kImplicitEuler, "ie"},
                                                                                {solvers::kFilteredFull, "full"}}) {
    const auto mine = [&](std::size_t r) { return a.text(r, "solver") == s && ok(r); };
    const auto dt = column(a, "dt", mine), integ = column(a, "error_vs_cvode", mine),
               total = column(a, "error_vs_fem", mine);
    out.files.emplace_back("conv_" + file + ".dat", series("dt error total", {dt, integ, total}));
    out.number(file == "ie" ? "vtbIEOrder" : "vtbFullOrder", loglog_slope(dt, integ), 2);
  }
  const auto cv = [&](std::size_t r) { return a.text(r, "solver") == solvers::kCvode && ok(r); };
  out.files.emplace_back("conv_cvode.dat",
                         series("rtol error", {column(a, "rtol", cv), column(a, "error_vs_cvode", cv)}));
  const CsvTable d = CsvTable::read(dir / "decomposition.csv");
  for (std::size_t r = 0; r < d.rows(); ++r)
    if (d.text(r, "run") == solvers::kCvode && d.text(r, "against") == solvers::kFem) {
      const double model = d.number(r, "displacement_error_max");
      out.number("vtbModelErr", model, 2);
      const auto fixed = [&](std::size_t q) {
        return a.text(q, "solver") == solvers::kFilteredFull || a.text(q, "solver") == solvers::kImplicitEuler;
      };
      const auto dts = column(a, "dt", fixed);
      const double lo = *std::min_element(dts.begin(), dts.end()), hi = *std::max_element(dts.begin(), dts.end());
      out.files.emplace_back("model_err.dat", series("dt error", {{lo, hi}, {model, model}}));
    }
}

} // namespace

void accuracy(const std::filesystem::path& dir, Out& out) {
  const CsvTable a = CsvTable::read(dir / "accuracy_speed.csv");
  const CsvTable meta = CsvTable::read(dir / "meta.csv");
  double duration = 1;
  for (std::size_t r = 0; r < meta.rows(); ++r)
    if (meta.text(r, "key") == "duration_s") duration = meta.number(r, "value");
  // Cost = wall time per simulated second: a cheap step at a tiny dt is not cheap.
  std::vector<Point> points;
  // A run identical to the reference (the FEM at the reference's own step) has error 0: no
  // measurement, and no place on a log axis.
  const auto ok = [&](std::size_t r) {
    return a.text(r, "stable") == "true" && std::isfinite(a.number(r, "error_vs_fem")) &&
           a.number(r, "error_vs_fem") > 0;
  };
  // Every solver the figure draws has its series, empty if the run had none (a reproduction
  // made before Bullet was a peer has no bullet rows).
  std::vector<std::string> names = distinct(a, "solver");
  if (std::find(names.begin(), names.end(), solvers::kBullet) == names.end()) names.push_back(solvers::kBullet);
  for (const std::string& s : names) {
    const auto mine = [&](std::size_t r) { return a.text(r, "solver") == s && ok(r); };
    std::vector<double> cost = column(a, "wall_seconds", mine), err = column(a, "error_vs_fem", mine);
    for (double& c : cost) c /= duration;
    for (std::size_t i = 0; i < cost.size(); ++i) points.push_back({cost[i], err[i], s});
    out.files.emplace_back("acc_" + s + ".dat", series("cost error", {cost, err}));
  }
  pareto(points, out);
  convergence(dir, a, ok, out);
}

void stability(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "stability.csv");
  for (const std::string& s : distinct(t, "solver"))
    for (const bool stable : {true, false}) {
      const auto mine = [&](std::size_t r) {
        return t.text(r, "solver") == s && (t.text(r, "stable") == "true") == stable;
      };
      out.files.emplace_back("stab_" + s + (stable ? "_ok" : "_bad") + ".dat",
                             series("dt scale", {column(t, "dt", mine), column(t, "stiffness_scale", mine)}));
    }
  std::map<double, double> courant; // scale -> predicted explicit limit
  for (std::size_t r = 0; r < t.rows(); ++r) courant[t.number(r, "stiffness_scale")] = t.number(r, "courant_dt");
  std::vector<double> cd, cs;
  for (const auto& [scale, dt] : courant) {
    cd.push_back(dt);
    cs.push_back(scale);
  }
  out.files.emplace_back("courant.dat", series("dt scale", {cd, cs}));
  const auto ratio = [&](const std::string& s, bool stable, bool largest) {
    double v = largest ? 0.0 : std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < t.rows(); ++r)
      if (t.text(r, "solver") == s && (t.text(r, "stable") == "true") == stable)
        v = largest ? std::max(v, t.number(r, "dt_over_courant")) : std::min(v, t.number(r, "dt_over_courant"));
    return std::isfinite(v) && v > 0 ? v : std::nan("");
  };
  out.number("vtbNbMaxStableRatio", ratio(solvers::kFilteredNeighbors, true, true), 2);
  out.number("vtbNbMinUnstableRatio", ratio(solvers::kFilteredNeighbors, false, false), 2);
  out.number("vtbExplicitMinUnstableRatio", ratio(solvers::kExplicit, false, false), 2);
  for (const auto& [s, name] : std::vector<std::pair<std::string, std::string>>{
           {solvers::kFilteredFull, "vtbFullStable"}, {solvers::kImplicitEuler, "vtbIEStable"}}) {
    int n = 0, ok = 0;
    for (std::size_t r = 0; r < t.rows(); ++r)
      if (t.text(r, "solver") == s) {
        ++n;
        ok += t.text(r, "stable") == "true";
      }
    out.macro(name, std::to_string(ok) + " of " + std::to_string(n));
  }
  out.number("vtbFullMaxRatio", ratio(solvers::kFilteredFull, true, true), 3);
}

void creep_scaling(const std::filesystem::path& dir, Out& out) {
  const CsvTable c = CsvTable::read(dir / "creep.csv");
  const auto all = [](std::size_t) { return true; };
  const auto t = column(c, "t", all), law = column(c, "analytic", all), full = column(c, "filtered_full", all),
             ie = column(c, "implicit_euler", all), cv = column(c, solvers::kCvode, all);
  const auto mm_of = [](std::vector<double> v) {
    for (double& x : v) x *= 1e3;
    return v;
  };
  out.files.emplace_back("creep.dat",
                         series("t analytic full ie cvode", {t, mm_of(law), mm_of(full), mm_of(ie), mm_of(cv)}));
  out.number("vtbCreepFullErr", 100 * max_relative_deviation(full, law), 2);
  out.number("vtbCreepIEErr", 100 * max_relative_deviation(ie, law), 2);
  out.number("vtbCreepCvodeErr", 100 * max_relative_deviation(cv, law), 2);

  const CsvTable s = CsvTable::read(dir / "scaling.csv");
  for (const int dim : {2, 3})
    for (const auto& [solver, tag] : std::vector<std::pair<std::string, std::string>>{
             {solvers::kFilteredFull, "Full"}, {solvers::kImplicitEuler, "IE"}}) {
      const std::string family = dim == 2 ? "rectangle" : "box"; // the structured ladders
      const auto mine = [&](std::size_t r) { return s.text(r, "family") == family && s.text(r, "solver") == solver; };
      const auto nodes = column(s, "nodes", mine), step = column(s, "step_median_us", mine),
                 pre = column(s, "precompute_ms", mine), heap = column(s, "heap_mb", mine);
      const std::string d = dim == 2 ? "Two" : "Three";
      out.files.emplace_back("scaling_" + std::to_string(dim) + "_" + solver + ".dat",
                             series("nodes step precompute heap", {nodes, step, pre, heap}));
      out.number("vtbExpStep" + tag + d, loglog_slope(nodes, step), 2);
      out.number("vtbExpHeap" + tag + d, loglog_slope(nodes, heap), 2);
      if (!nodes.empty()) {
        if (tag == "Full") out.number("vtbMaxNodes" + d, nodes.back(), 4);
        out.number("vtbMaxStep" + tag + d, step.back());
      }
    }
  // The CGAL slab ladder (3D at haptic rate): one row per mesh and solver.
  std::ostringstream slab;
  for (std::size_t r = 0; r < s.rows(); ++r) {
    if (s.text(r, "family") != "cgal-slab") continue;
    const double heap = s.number(r, "heap_mb");
    // The default (filter = auto) marked beside the named filters (a reproduction made before
    // the column has no mark).
    const bool picked = s.has_column("auto_pick") && s.text(r, "auto_pick") == "true";
    slab << tex_number(s.number(r, "nodes")) << " & \\texttt{" << tex_escape(s.text(r, "solver")) << "}"
         << (picked ? "$^\\dagger$" : "") << " & " << tex_number(s.number(r, "step_median_us") / 1e3) << " & "
         << tex_number(s.number(r, "precompute_ms")) << " & "
         << (std::isfinite(heap) ? tex_number(heap) : std::string("--")) << " & "
         << tex_number(100 * s.number(r, "error_vs_fem")) << " \\\\\n";
  }
  out.files.emplace_back("slab_rows.tex", slab.str());
  out.number("vtbAutoMultigridNodes", static_cast<double>(kScalarCycleFreeNodes3D)); // the auto filter's thresholds
  out.number("vtbAutoTensorCycleNodes", static_cast<double>(kTensorCycleFreeNodes3D));
}

void haptics(const std::filesystem::path& dir, Out& out) {
  const CsvTable p = CsvTable::read(dir / "haptics_periods.csv");
  const auto all = [](std::size_t) { return true; };
  std::vector<double> periods = column(p, "period_us", all);
  if (!periods.empty()) {
    const double lo = std::floor(*std::min_element(periods.begin(), periods.end()));
    const double hi = std::ceil(*std::max_element(periods.begin(), periods.end())) + 1;
    const int bins = 60;
    std::vector<double> edge(bins + 1), count(bins + 1, 0.0);
    for (int b = 0; b <= bins; ++b) edge[b] = lo + (hi - lo) * b / bins;
    for (double v : periods) count[std::min(bins - 1, static_cast<int>((v - lo) / (hi - lo) * bins))] += 1;
    count[bins] = count[bins - 1]; // ybar interval: the last edge closes the last bin
    out.files.emplace_back("haptics_hist.dat", series("edge count", {edge, count}));
  }
  const CsvTable tr = CsvTable::read(dir / "haptics_trace.csv");
  out.files.emplace_back("haptics_trace.dat",
                         series("t force hy", {column(tr, "t", all), column(tr, "force", all), column(tr, "hy", all)}));
  const CsvTable s = CsvTable::read(dir / "haptics_summary.csv");
  out.number("vtbServoRate", s.number(0, "rate_hz"), 4);
  out.number("vtbServoPNineNine", s.number(0, "period_p99_us"), 4);
  out.number("vtbServoMax", s.number(0, "period_max_us"), 4);
  out.number("vtbMisses", s.number(0, "deadline_misses"));
  out.number("vtbServoSamples", s.number(0, "samples"), 6);
  out.number_and_raw("vtbStallTime", s.number(0, "stall_time"));
  out.number("vtbFaultTime", s.number(0, "fault_time"), 4);
  out.number("vtbForceZeroMs", 1e3 * (s.number(0, "force_zero_time") - s.number(0, "fault_time")), 3);
  out.number("vtbMaxForce", s.number(0, "max_force"), 3);
  out.number_and_raw("vtbDeviceLimit", s.number(0, "device_limit"), 3);
}

void multirate(const std::filesystem::path& dir, Out& out) {
  // The force per servo cycle on the 10k slab, lockstep at 1 kHz and real time at the rate the
  // body affords; the numbers: the body, the physics' step and pace, the held forces and their
  // cycle-to-cycle steadiness, the servo's cost.
  const CsvTable tr = CsvTable::read(dir / "multirate_trace.csv");
  const auto all = [](std::size_t) { return true; };
  out.files.emplace_back(
      "multirate_trace.dat",
      series("t lockstep realtime", {column(tr, "t", all), column(tr, "lockstep", all), column(tr, "realtime", all)}));
  const CsvTable s = CsvTable::read(dir / "multirate_summary.csv");
  const double lock = s.number(0, "held_lockstep"), rt = s.number(0, "held_realtime");
  out.number("vtbMrNodes", s.number(0, "nodes"), 6);
  out.number("vtbMrDtMs", 1e-3 * s.number(0, "physics_dt_us"), 3);
  out.number("vtbMrRatio", s.number(0, "physics_time_ratio"), 3);
  out.number("vtbMrStepMs", 1e-3 * s.number(0, "physics_step_median_us"), 3);
  out.number("vtbMrLockStepMs", 1e-3 * s.number(0, "lockstep_step_median_us"), 3);
  out.number("vtbMrHeldLock", lock, 3);
  out.number("vtbMrHeldRt", rt, 3);
  out.number("vtbMrHeldDiff", 100 * std::abs(rt - lock) / lock, 2);
  out.number("vtbMrChangeLock", 100 * s.number(0, "change_lockstep") / lock, 2);
  out.number("vtbMrChangeRt", 100 * s.number(0, "change_realtime") / rt, 2);
  out.number("vtbMrTickMedian", s.number(0, "tick_median_us"), 3);
  out.number("vtbMrTickPNineNine", s.number(0, "tick_p99_us"), 3);
  out.number("vtbMrMisses", s.number(0, "deadline_misses"));
}

void tip_force(const std::filesystem::path& dir, Out& out) {
  // The held force against depth (mm) per mesh, with the tool tip and with a point proxy, and
  // the half-space's line; the numbers: the two meshes' forces at the deepest press and their
  // spread, with the tip and without.
  const CsvTable t = CsvTable::read(dir / "tip_force.csv");
  const auto rows = [&](const std::string& mesh, bool tip) {
    return
        [&t, mesh, tip](std::size_t r) { return t.text(r, "mesh") == mesh && (t.number(r, "tip_radius") > 0) == tip; };
  };
  const auto depth_mm = [](std::vector<double> d) {
    for (double& v : d) v *= 1e3;
    return d;
  };
  const auto deepest = [&](const std::string& mesh, bool tip) {
    const std::vector<double> f = column(t, "force", rows(mesh, tip));
    return f.empty() ? std::nan("") : f.back();
  };
  out.files.emplace_back("tip_anchor.dat",
                         series("depth force", {depth_mm(column(t, "depth", rows("half-space", true))),
                                                column(t, "force", rows("half-space", true))}));
  for (const char* mesh : {"slab_500", "slab_2000"})
    for (const bool tip : {true, false}) {
      const auto keep = rows(std::string(mesh) + ".msh", tip);
      out.files.emplace_back(std::string("tip_") + mesh + (tip ? "_tip" : "_point") + ".dat",
                             series("depth force", {depth_mm(column(t, "depth", keep)), column(t, "force", keep)}));
    }
  const double coarse = deepest("slab_500.msh", true), fine = deepest("slab_2000.msh", true);
  out.number("vtbTipCoarse", coarse, 3);
  out.number("vtbTipFine", fine, 3);
  out.number("vtbTipSpread", 100 * std::abs(coarse - fine) / fine, 2);
  out.number("vtbPointCoarse", deepest("slab_500.msh", false), 3);
  out.number("vtbPointFine", deepest("slab_2000.msh", false), 3);
  const std::vector<double> anchor = column(t, "force", rows("half-space", true));
  out.number("vtbTipAnchor", anchor.empty() ? std::nan("") : anchor.back(), 3);
  const std::vector<double> depths = column(t, "depth", rows("half-space", true));
  out.number("vtbTipDepthMm", depths.empty() ? std::nan("") : 1e3 * depths.back(), 2);
}

namespace {

/// The force at which a model's curve (through the origin, in file order) reaches `depth`
/// (a share of the layer), by linear interpolation; NaN beyond its deepest converged point.
double force_at_depth(const std::vector<double>& depth, const std::vector<double>& force, double target) {
  double d0 = 0, f0 = 0;
  for (std::size_t k = 0; k < depth.size(); ++k) {
    if (!std::isfinite(depth[k])) break;
    if (depth[k] >= target && depth[k] > d0) return f0 + (force[k] - f0) * (target - d0) / (depth[k] - d0);
    d0 = depth[k], f0 = force[k];
  }
  return std::nan("");
}

} // namespace

void deep_press(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "deep_press.csv");
  const auto rows = [&t](const std::string& nu, const std::string& model) {
    return [&t, nu, model](std::size_t r) { return t.text(r, "poisson_ratio") == nu && t.text(r, "model") == model; };
  };
  const std::pair<const char*, const char*> materials[] = {{"0.3", "A"}, {"0.45", "B"}};
  for (const auto& [nu, tag] : materials) {
    std::vector<double> nh_depth, nh_force;
    for (const char* model :
         {"linear-p2", "springs", "springs-volume", "springs-fitted-volume", "springs-fitted-stable",
          "springs-fitted-nodal", "neo-hookean-p2", "neo-hookean-p1", "svk-p1"}) {
      const std::vector<double> depth = column(t, "depth_ratio", rows(nu, model));
      const std::vector<double> force = column(t, "force", rows(nu, model));
      std::vector<double> pct{0.0}, mn{0.0}; // the plot's units: % of the layer, mN; every curve starts at rest
      for (std::size_t k = 0; k < depth.size(); ++k)
        if (std::isfinite(depth[k])) pct.push_back(100 * depth[k]), mn.push_back(1e3 * force[k]);
      out.files.emplace_back(std::string("deep_") + tag + "_" + model + ".dat", series("depth force", {pct, mn}));
      if (std::string(model) == "neo-hookean-p2") nh_depth = depth, nh_force = force;
    }
    // The gaps: a model's force at a depth against the neo-Hookean continuum's, in per cent.
    const auto gap = [&](const char* model, double d) {
      const double f =
          force_at_depth(column(t, "depth_ratio", rows(nu, model)), column(t, "force", rows(nu, model)), d);
      return 100 * (f / force_at_depth(nh_depth, nh_force, d) - 1);
    };
    const std::string T = tag;
    out.number("vtbDeepSpringsTen" + T, gap("springs", 0.1), 2);
    out.number("vtbDeepSpringsTwenty" + T, gap("springs", 0.2), 2);
    out.number("vtbDeepSpringsThirty" + T, gap("springs", 0.3), 2);
    out.number("vtbDeepVolumeTen" + T, gap("springs-volume", 0.1), 2);
    out.number("vtbDeepVolumeTwenty" + T, gap("springs-volume", 0.2), 2);
    out.number("vtbDeepVolumeThirty" + T, gap("springs-volume", 0.3), 2);
    out.number("vtbDeepVolumeFifty" + T, gap("springs-volume", 0.5), 2);
    out.number("vtbDeepFitVolumeTen" + T, gap("springs-fitted-volume", 0.1), 2);
    out.number("vtbDeepFitVolumeTwenty" + T, gap("springs-fitted-volume", 0.2), 2);
    out.number("vtbDeepFitVolumeThirty" + T, gap("springs-fitted-volume", 0.3), 2);
    out.number("vtbDeepFitVolumeFifty" + T, gap("springs-fitted-volume", 0.5), 2);
    out.number("vtbDeepStableTen" + T, gap("springs-fitted-stable", 0.1), 2);
    out.number("vtbDeepStableTwenty" + T, gap("springs-fitted-stable", 0.2), 2);
    out.number("vtbDeepStableThirty" + T, gap("springs-fitted-stable", 0.3), 2);
    out.number("vtbDeepStableFifty" + T, gap("springs-fitted-stable", 0.5), 2);
    out.number("vtbDeepNodalTen" + T, gap("springs-fitted-nodal", 0.1), 2);
    out.number("vtbDeepNodalTwenty" + T, gap("springs-fitted-nodal", 0.2), 2);
    out.number("vtbDeepNodalThirty" + T, gap("springs-fitted-nodal", 0.3), 2);
    out.number("vtbDeepNodalFifty" + T, gap("springs-fitted-nodal", 0.5), 2);
    // The most cells inverted at once in any run of a network (summary.json's inverted_cells).
    const auto inverted = [&](const char* model) {
      const std::vector<double> v = column(t, "inverted_cells", rows(nu, model));
      return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end());
    };
    out.number("vtbDeepSpringsInverted" + T, inverted("springs"), 6);
    out.number("vtbDeepVolumeInverted" + T, inverted("springs-volume"), 6);
    out.number("vtbDeepFitVolumeInverted" + T, inverted("springs-fitted-volume"), 6);
    out.number("vtbDeepStableInverted" + T, inverted("springs-fitted-stable"), 6);
    out.number("vtbDeepNodalInverted" + T, inverted("springs-fitted-nodal"), 6);
    out.number("vtbDeepLinearThirty" + T, gap("linear-p2", 0.3), 2);
    out.number("vtbDeepPOneThirty" + T, gap("neo-hookean-p1", 0.3), 2); // the discretisation's share
    // How far one uniform refinement moves the neo-Hookean reference's depth at 0.5 F30 (the
    // harness's one refined solve against the path's level on the mesh), in per cent.
    const auto depth_at = [&](const char* model, double level) {
      const std::vector<double> d = column(t, "depth", rows(nu, model)), l = column(t, "level", rows(nu, model));
      for (std::size_t k = 0; k < l.size(); ++k)
        if (std::abs(l[k] - level) < 1e-9) return d[k];
      return std::nan("");
    };
    out.number("vtbDeepRefinedHalf" + T,
               100 * (depth_at("neo-hookean-p2-refined", 0.5) / depth_at("neo-hookean-p2", 0.5) - 1), 2);
    std::vector<double> svk = column(t, "depth_ratio", rows(nu, "svk-p1")),
                        levels = column(t, "level", rows(nu, "svk-p1"));
    // Where St. Venant-Kirchhoff collapses: the last level of a path that stops (Newton finds no
    // equilibrium past the limit point; the levels after it are missing), or, where Newton finds
    // the collapsed equilibrium beyond it and the path goes on, the level after which the depth
    // jumps most between two levels.
    std::size_t reached = 0;
    while (reached < svk.size() && std::isfinite(svk[reached])) ++reached;
    const bool stopped = reached < column(t, "level", rows(nu, "linear-p2")).size();
    double svk_last = stopped && reached > 0 ? levels[reached - 1] : 0, jump = -1;
    for (std::size_t k = 0; !stopped && k + 1 < reached; ++k)
      if (svk[k + 1] - svk[k] > jump) jump = svk[k + 1] - svk[k], svk_last = levels[k];
    out.number("vtbDeepSvkLast" + T, svk_last, 3);
    const std::vector<double> lf = column(t, "force", rows(nu, "linear-p2")),
                              ld = column(t, "depth_ratio", rows(nu, "linear-p2"));
    out.number("vtbDeepFThirty" + T, lf.empty() ? std::nan("") : 1e3 * lf[0] * 0.3 / ld[0], 3); // linear: F30
  }
  out.number("vtbDeepNodes", column(t, "nodes", [](std::size_t) { return true; }).front(), 6);
}

} // namespace vtb::reproduction::paper
