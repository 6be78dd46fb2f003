#include "vtb/reproduction/reproduce.hh"
#include "vtb/harness/ranks.hh"
#include "vtb/problem/solver_registry.hh"

#include "reproduce_parts.hh"

#include "vtb/problem/cell_fields.hh"

#include "vtb/harness/compare.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/harness/sweep.hh"
#include "vtb/meshes/vtu_io.hh"
#include "vtb/problem/output.hh"
#include "vtb/reproduction/bench_scale.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>

namespace vtb::reproduction {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables
namespace {

using clock_type = std::chrono::steady_clock;

struct Case {
  std::string label, scene_file;
  int forces = 1;
  double paper_fps = 0; ///< the paper's frames per second on a Pentium III-450
};

struct TimingRow {
  std::string label, solver;
  int nodes = 0, forces = 0;
  double paper_fps = 0, dt = 0, steps_per_second = 0, step_us = 0, precompute_ms = 0, realtime = 0, error = 0;
  double step_min_us = 0, step_max_us = 0; ///< over the repetitions' medians (step_us: their median)
  int repeats = 1;
  bool stable = true, timing_only = false;
};

/// How often the timing table times each solver after the run that measures its error (which
/// warms caches and the allocator): one run's median step moved from 14.5 to 23.9 us between two
/// reproductions on one machine; the median of several runs' medians is what the table reports,
/// with their minimum and maximum beside it.
int timing_repeats(bool quick) {
  return quick ? 3 : 5;
}

std::string fmt(double x, int prec = 3) {
  if (std::isnan(x)) return "n/a";
  std::ostringstream os;
  os << std::setprecision(prec) << x;
  return os.str();
}

void write_text(const std::filesystem::path& p, const std::string& text) {
  write_files_atomically(p.parent_path(), {{p.filename().string(), text}});
}

/// Field snapshots of one run for the Fig. 3 analogue: CSV and VTU at the requested times.
void write_fig3(const std::filesystem::path& dir, const std::string& solver, const Model<2>& model,
                const Trajectory<2>& tr, const std::vector<double>& times) {
  for (double t : times) {
    std::size_t k = 0;
    for (std::size_t j = 0; j < tr.t.size(); ++j)
      if (std::abs(tr.t[j] - t) < std::abs(tr.t[k] - t)) k = j;
    std::ostringstream name;
    name << solver << "_t" << std::fixed << std::setprecision(1) << t;
    std::ostringstream csv;
    csv << std::setprecision(10) << "node,x,y,ux,uy\n";
    for (int i = 0; i < model.num_nodes(); ++i)
      csv << i << ',' << model.mesh.points(0, i) << ',' << model.mesh.points(1, i) << ',' << tr.field[k](0, i) << ','
          << tr.field[k](1, i) << '\n';
    std::vector<float> strain;
    cell_max_principal_strain(model.mesh, tr.field[k], strain);
    std::ostringstream cells;
    cells << std::setprecision(6) << "cell,n0,n1,n2,max_principal_strain\n";
    for (int c = 0; c < model.mesh.num_cells(); ++c) {
      const auto& cell = model.mesh.cells[static_cast<std::size_t>(c)];
      cells << c << ',' << cell[0] << ',' << cell[1] << ',' << cell[2] << ',' << strain[static_cast<std::size_t>(c)]
            << '\n';
    }
    write_files_atomically(dir, {{name.str() + ".csv", csv.str()}, {name.str() + "_cells.csv", cells.str()}});
    write_vtu(model.mesh, dir / (name.str() + ".vtu"),
              {point_vectors<2>("displacement", tr.field[k]),
               VtuField{"max_principal_strain", 1, true, std::vector<double>(strain.begin(), strain.end())}});
  }
}

/// What the timing part hands to the rest: the table, the decomposition on the first case,
/// and that case's filtered-full and FEM runs for the Fig. 3 analogue.
struct TimingPart {
  std::vector<TimingRow> table;
  std::vector<DecompositionRow> decomposition;
  Model<2> fig_model;
  std::map<std::string, Trajectory<2>> fig_runs;
};

Scene scene_for(const ReproduceOptions& o, const std::string& file, double duration) {
  Scene s = read_scene(o.scenes_dir / file);
  s.duration = duration;
  return s;
}

/// The explicit scheme timed over a bounded number of steps at half its limit: over the whole
/// run it would take hours at the plates' damping-limited step.
TimingRow explicit_timing_row(const Scene& scene, const Model<2>& model, const Case& cs, double duration) {
  const double tau = scene.material.retardation_time;
  const double dtc = explicit_critical_dt(max_omega_squared(model, true), tau, scene.material.mass_damping);
  Model<2> m = model;
  m.duration = std::min(duration, 20000 * 0.5 * dtc);
  m.output_interval = m.duration;
  Trajectory<2> tr;
  IntegratorOptions io;
  io.kind = solvers::kExplicit;
  io.dt = 0.5 * dtc;
  const auto a = clock_type::now();
  const RunReport rep = simulate(m, io, tr);
  const double w = std::chrono::duration<double>(clock_type::now() - a).count();
  TimingRow r;
  r.label = cs.label;
  r.solver = solvers::kExplicit;
  r.nodes = model.num_nodes();
  r.forces = cs.forces;
  r.paper_fps = cs.paper_fps;
  r.dt = io.dt;
  r.stable = rep.stable;
  r.steps_per_second = 1.0 / rep.step_seconds.mean;
  r.step_us = rep.step_seconds.median * 1e6;
  r.precompute_ms = rep.precompute_seconds * 1e3;
  r.realtime = m.duration / w;
  r.error = std::nan("");
  r.timing_only = true;
  return r;
}

/// (a) The timing table, with the error of each solver against the FEM.
TimingPart run_timing(const ReproduceOptions& o, double duration) {
  std::ostream* log = o.progress;
  const std::vector<Case> cases = {{"517 nodes, one force", "plate517_step.toml", 1, 25.0},
                                   {"517 nodes, four forces", "plate517_four_forces.toml", 4, 25.0},
                                   {"123 nodes, one force", "plate123_step.toml", 1, 100.0}};
  const std::vector<std::string> solvers = {solvers::kFilteredNeighbors, solvers::kFilteredFull,
                                            solvers::kImplicitEuler, solvers::kCvode, solvers::kFem};
  TimingPart part;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const Case& cs = cases[c];
    if (log) *log << "[timing " << c + 1 << "/" << cases.size() << "] " << cs.label << "\n";
    const Scene scene = scene_for(o, cs.scene_file, duration);
    const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb run builds them
    const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)), {}, true, &yardstick);
    std::map<std::string, Trajectory<2>> runs;
    std::map<std::string, RunReport> reports;
    std::map<std::string, double> wall;
    std::map<std::string, std::vector<double>> step_us, walls; // per repetition
    for (const auto& s : solvers) {
      if (log) *log << "  " << s << " ..." << std::flush;
      const auto a = clock_type::now();
      reports[s] = run_solver(scene, model, s, 0, runs[s]);
      wall[s] = std::chrono::duration<double>(clock_type::now() - a).count();
      if (log) *log << " " << fmt(wall[s]) << " s" << (reports[s].stable ? "" : " (unstable)") << std::flush;
      for (int k = 0; k < timing_repeats(o.quick) && reports[s].stable; ++k) {
        Trajectory<2> again;
        const auto b = clock_type::now();
        const RunReport rep = run_solver(scene, model, s, 0, again);
        walls[s].push_back(std::chrono::duration<double>(clock_type::now() - b).count());
        step_us[s].push_back(rep.step_seconds.median * 1e6);
      }
      if (log) *log << ", timed " << step_us[s].size() << " times more\n";
    }
    for (const auto& s : solvers) {
      TimingRow r;
      r.label = cs.label;
      r.solver = s;
      r.nodes = model.num_nodes();
      r.forces = cs.forces;
      r.paper_fps = cs.paper_fps;
      const RunReport& rep = reports[s];
      r.dt = rep.dt;
      r.stable = rep.stable;
      r.steps_per_second = rep.step_seconds.mean > 0 ? 1.0 / rep.step_seconds.mean : 0;
      r.step_us = rep.step_seconds.median * 1e6;
      r.step_min_us = r.step_max_us = r.step_us;
      r.precompute_ms = rep.precompute_seconds * 1e3;
      r.realtime = (rep.stable ? duration : rep.failure_time) / wall[s];
      if (!step_us[s].empty()) { // the repetitions' median, and their spread
        std::vector<double> us = step_us[s], w = walls[s];
        std::sort(us.begin(), us.end());
        std::sort(w.begin(), w.end());
        r.repeats = static_cast<int>(us.size());
        r.step_us = us[us.size() / 2];
        r.step_min_us = us.front();
        r.step_max_us = us.back();
        r.steps_per_second = 1e6 / r.step_us;
        r.realtime = duration / w[w.size() / 2];
      }
      r.error = rep.stable ? compare(runs[s], runs[solvers::kFem]).displacement_max : std::nan("");
      part.table.push_back(r);
    }
    part.table.push_back(explicit_timing_row(scene, model, cs, duration));
    if (c != 0) continue;
    for (const char* a : {solvers::kFilteredFull, solvers::kFilteredNeighbors}) {
      if (!reports[a].stable) continue;
      part.decomposition.push_back(
          {a, solvers::kCvode, "time-integration error of the approximation", compare(runs[a], runs[solvers::kCvode])});
      part.decomposition.push_back({a, solvers::kFem, "what a user sees", compare(runs[a], runs[solvers::kFem])});
    }
    part.decomposition.push_back({solvers::kImplicitEuler, solvers::kCvode, "time-integration error of implicit Euler",
                                  compare(runs[solvers::kImplicitEuler], runs[solvers::kCvode])});
    part.decomposition.push_back({solvers::kCvode, solvers::kFem, "modelling error of springs vs continuum",
                                  compare(runs[solvers::kCvode], runs[solvers::kFem])});
    part.fig_model = model;
    part.fig_runs[solvers::kFilteredFull] = std::move(runs[solvers::kFilteredFull]);
    part.fig_runs[solvers::kFem] = std::move(runs[solvers::kFem]);
  }
  return part;
}

/// (c) Accuracy against speed on the 123-node plate: a dt ladder per solver.
void write_accuracy(const ReproduceOptions& o, double duration) {
  std::ostream* log = o.progress;
  if (log) *log << "[accuracy vs speed] 123-node plate\n";
  std::ostringstream acc;
  acc << "solver,dt,rtol,stable,error_vs_cvode,error_vs_fem,wall_seconds,step_median_us\n";
  const Scene scene = scene_for(o, "plate123_step.toml", duration);
  const Yardstick yardstick = continuum_yardstick(); // the default springs, as vtb run builds them
  const Model<2> model = build_model<2>(scene, std::get<Mesh2>(load_mesh(scene)), {}, true, &yardstick);
  Scene tight = scene;
  tight.solver.cvode.rtol = 1e-10;
  tight.solver.cvode.atol = 1e-14;
  Trajectory<2> ref_cvode, ref_fem;
  run_solver(tight, model, solvers::kCvode, 0, ref_cvode);
  run_solver(scene, model, solvers::kFem, scene.solver.dt / 4, ref_fem);
  const std::vector<double> ladder =
      o.quick ? std::vector<double>{0.04, 0.01, 0.0025} : std::vector<double>{0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125};
  auto row = [&](const std::string& solver, const Scene& sc, double dt, double rtol) {
    Trajectory<2> tr;
    const auto a = clock_type::now();
    const RunReport rep = run_solver(sc, model, solver, dt, tr);
    const double w = std::chrono::duration<double>(clock_type::now() - a).count();
    const bool ok = rep.stable;
    acc << solver << ',' << fmt(rep.dt, 6) << ',' << (rtol > 0 ? fmt(rtol) : "") << ',' << (ok ? "true" : "false")
        << ',' << (ok ? fmt(compare(tr, ref_cvode).displacement_max, 6) : "nan") << ','
        << (ok ? fmt(compare(tr, ref_fem).displacement_max, 6) : "nan") << ',' << fmt(w, 6) << ','
        << fmt(rep.step_seconds.median * 1e6, 6) << '\n';
    if (log) *log << "  " << solver << " dt " << fmt(rep.dt) << (ok ? "" : " (unstable)") << "\n";
  };
  for (const char* s :
       {solvers::kFilteredFull, solvers::kFilteredNeighbors, solvers::kImplicitEuler, solvers::kBullet, solvers::kFem})
    for (double dt : ladder) row(s, scene, dt, 0);
  for (double rtol : o.quick ? std::vector<double>{1e-3, 1e-6} : std::vector<double>{1e-2, 1e-4, 1e-6, 1e-8}) {
    Scene sc = scene;
    sc.solver.cvode.rtol = rtol;
    sc.solver.cvode.atol = rtol * 1e-4;
    row(solvers::kCvode, sc, 0, rtol);
  }
  row(solvers::kExplicit, scene, 0, 0); // half its stability limit
  write_text(o.out / "accuracy_speed.csv", acc.str());
}

/// spring_fit.csv: the fit's cost on clamped CGAL slabs (the default springs fit, docs/fidelity.md),
/// 1k- and 2k-node slabs when quick (about 20 s), else the ladder of `vtb bench scale`.
void write_fit_cost(const ReproduceOptions& o) {
  const std::vector<int> slabs = o.quick ? std::vector<int>{1000, 2000} : std::vector<int>{1000, 2000, 5000, 10000};
  write_files_atomically(o.out, {{"spring_fit.csv", fit_ladder(slabs, o.progress)}});
}

/// (d) The stability map on the 123-node plate.
void write_stability(const ReproduceOptions& o) {
  if (o.progress) *o.progress << "[stability map]\n";
  Scene scene = scene_for(o, "plate123_step.toml", o.quick ? 0.5 : 1.0);
  const std::vector<double> dts =
      o.quick ? std::vector<double>{1e-5, 1e-3, 2e-2} : std::vector<double>{1e-5, 1e-4, 1e-3, 1e-2, 4e-2};
  const std::vector<double> scales =
      o.quick ? std::vector<double>{0.1, 10.0} : std::vector<double>{0.01, 0.1, 1.0, 10.0, 100.0};
  write_sweep(
      run_sweep(scene, dts, scales,
                {solvers::kExplicit, solvers::kFilteredNeighbors, solvers::kFilteredFull, solvers::kImplicitEuler},
                o.progress, false), // one part of the reproduction: this rank runs it whole
      o.out / "stability.csv");
}

void write_timing_csv(const ReproduceOptions& o, const TimingPart& part) {
  std::ostringstream csv, dcsv;
  csv << "case,nodes,forces,paper_fps_piii450,solver,dt,stable,steps_per_second,step_median_us,precompute_ms,"
         "realtime_factor,displacement_error_vs_fem,timing_only,step_min_us,step_max_us,timing_repeats\n";
  for (const auto& r : part.table)
    csv << '"' << r.label << "\"," << r.nodes << ',' << r.forces << ',' << r.paper_fps << ',' << r.solver << ','
        << fmt(r.dt, 6) << ',' << (r.stable ? "true" : "false") << ',' << fmt(r.steps_per_second, 6) << ','
        << fmt(r.step_us, 6) << ',' << fmt(r.precompute_ms, 6) << ',' << fmt(r.realtime, 6) << ',' << fmt(r.error, 6)
        << ',' << (r.timing_only ? "true" : "false") << ',' << fmt(r.repeats > 1 ? r.step_min_us : r.step_us, 6) << ','
        << fmt(r.repeats > 1 ? r.step_max_us : r.step_us, 6) << ',' << r.repeats << '\n';
  dcsv << "run,against,meaning,displacement_error_max,displacement_error_final,reaction_error_max\n";
  for (const auto& d : part.decomposition)
    dcsv << d.a << ',' << d.b << ",\"" << d.meaning << "\"," << fmt(d.error.displacement_max, 6) << ','
         << fmt(d.error.displacement_final, 6) << ',' << fmt(d.error.reaction_max, 6) << '\n';
  write_files_atomically(o.out, {{"timing_table.csv", csv.str()}, {"decomposition.csv", dcsv.str()}});
}

/// report.md: the timing table and the decomposition as markdown, the files, and the figures
/// (PNG written beside it by scripts/build_paper.sh).
std::string report_markdown(const ReproduceOptions& o, const TimingPart& part, double duration) {
  std::ostringstream md;
  md << "# vtb reproduce" << (o.quick ? " --quick" : "") << "\n\n"
     << "Cai, Dill and Payandeh's experiment: a thin polygonal plate, clamped on its left edge and pulled by a step "
        "force (or four forces), "
     << duration << " s of simulated time. Machine: this one (2 cores); the paper: Pentium III-450, NT.\n\n"
     << "## Timing table\n\n"
     << "| case | paper (PIII-450) | solver | dt [s] | stable | us/step | steps/s | precompute [ms] | real-time factor "
        "| error vs FEM |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : part.table)
    md << "| " << r.label << " | " << r.paper_fps << " frames/s | " << r.solver << " | " << fmt(r.dt) << " | "
       << (r.stable ? "yes" : "**no**") << " | " << fmt(r.step_us) << " | " << fmt(r.steps_per_second) << " | "
       << fmt(r.precompute_ms) << " | " << fmt(r.realtime) << (r.timing_only ? " (timed over 20000 steps)" : "")
       << " | " << fmt(r.error) << " |\n";
  md << "\n## Error decomposition (517 nodes, one force)\n\n| run | against | meaning | max rel. L2 displacement error "
        "| final |\n|---|---|---|---|---|\n";
  for (const auto& d : part.decomposition)
    md << "| " << d.a << " | " << d.b << " | " << d.meaning << " | " << fmt(d.error.displacement_max) << " | "
       << fmt(d.error.displacement_final) << " |\n";
  md << "\n## Figures\n\nDrawn by `scripts/build_paper.sh` (pgfplots) from the CSV files here, as PNG in `figures/` "
        "and in the paper `vtb.pdf`; without LaTeX the links below stay empty.\n\n";
  for (const auto& [file, title] : kReportFigures) md << "![" << title << "](figures/" << file << ".png)\n\n";
  md << "## Files\n\n- `timing_table.csv`: the table above.\n- `fig3/`: the plate at 0, " << duration / 2 << " and "
     << duration << " s (CSV with the cells and their strain, and VTU), " << solvers::kFilteredFull
     << " and FEM (the paper's Fig. 3).\n"
        "- `accuracy_speed.csv`: error against CVODE (rtol 1e-10) and against the FEM, and cost, over a dt ladder per "
        "solver (123-node plate).\n- `stability.csv`: stable or not over dt x stiffness scale, with the explicit "
        "scheme's predicted limit (criterion: "
     << kStabilityCriterion
     << ").\n- `decomposition.csv`: the error decomposition.\n- `creep.csv`: the creep strip's tip against the "
        "Kelvin-Voigt law.\n- `scaling.csv`: step time, precompute and heap over a 2D and a 3D mesh ladder.\n"
        "- `fidelity.csv`: the springs' own error against the continuum and P1 FEM on the same mesh (both linear and "
        "static) per "
        "case and calibration (docs/fidelity.md).\n"
        "- `spring_fit.csv`: the spring fit's cost on clamped CGAL slabs (1k and 2k nodes when quick, else 1k to "
        "10k): wall time, steps, held-out error.\n"
        "- `haptics_*.csv`: a real-time servo session with a physics stall (periods, force trace, summary).\n"
        "- `tip_force.csv`: the slab press's held force against depth on two meshes, with the 4 mm tool tip and a "
        "point proxy, and the half-space's force.\n"
        "- `multirate_*.csv`: the slab press on a 10k-node CGAL slab, lockstep at 1 kHz against real time at the rate "
        "the body affords (the force per servo cycle, the physics' step, the servo's cost).\n"
        "- `deep_press.csv`: a soft layer pressed 40 % deep by a disc: the springs against linear P2, St. "
        "Venant-Kirchhoff and neo-Hookean (docs/fem.md).\n"
        "- `meta.csv`: quick or not, the machine.\n\n"
     << "Reading: the paper's frame rates were one step per frame on a 450 MHz Pentium III. The truncated "
        "(`neighbors`) filter is the paper's; at steps beyond a few explicit limits it diverges (docs/method.md), "
        "which the table records as unstable rather than hiding.\n";
  return md.str();
}

} // namespace

std::string run_reproduce(const ReproduceOptions& options) {
  const double duration = options.quick ? 2.0 : 10.0;
  // Under mpirun the parts are spread over the ranks: rank 0 runs the timing table (the report
  // is made of it), the others take the remaining parts from one queue (in the serial order)
  // and rank 0 joins them when done; the real-time haptics session runs last, on rank 0 alone,
  // once every other rank has finished, so that no other work shares the machine with its
  // servo thread. Each part writes its own files once; rank 0 alone prints and writes report.md.
  const Ranks w = world();
  ReproduceOptions o = options;
  if (!w.root()) o.progress = nullptr;
  bool shared = false;
  const std::string where = binding(&shared);
  if (w.root()) {
    ensure_directory(o.out);
    parts::write_meta(o.out, o.quick, duration, where);
  }
  barrier(); // the folder exists before any rank writes into it
  // Costliest first (a quick reproduction, serial, on this 2-core machine: scaling 81-88 s,
  // accuracy 38 s (its explicit run), stability 6 s, the rest under a second; the timing table,
  // rank 0's, 6 s).
  const std::vector<std::function<void()>> jobs = {
      [&] { parts::write_scaling(o.out, o.quick, o.progress); },
      [&] { write_accuracy(o, duration); },
      [&] { write_stability(o); },
      [&] { parts::write_fidelity(o.out, o.scenes_dir, o.progress); },
      [&] { write_fit_cost(o); },
      [&] { parts::write_creep(o.out, o.scenes_dir, o.progress); },
      [&] { parts::write_transient(o.out, o.scenes_dir, o.progress); },
      [&] { parts::write_tip_force(o.out, o.scenes_dir, o.quick, o.progress); },
      [&] { parts::write_deep_press(o.out, o.quick, o.progress); }};
  CellQueue queue(static_cast<long>(jobs.size()));
  TimingPart timing;
  if (w.root()) {
    timing = run_timing(o, duration);
    write_timing_csv(o, timing);
    // (b) The Fig. 3 analogue: the plate at 0, T/2 and T (the paper: 0, 5 and 10 s).
    if (o.progress) *o.progress << "[fig3] deformed shapes\n";
    for (const auto& [solver, tr] : timing.fig_runs)
      write_fig3(o.out / "fig3", solver, timing.fig_model, tr, {0.0, duration / 2, duration});
  }
  for (long k; (k = queue.next()) >= 0;) jobs[static_cast<std::size_t>(k)]();
  barrier();
  if (!w.root()) return {};
  if (shared && o.progress)
    *o.progress << "warning: two ranks of one node may have shared a core: timing columns may be each other's\n";
  parts::write_haptics(o.out, o.scenes_dir, 1.5, o.progress);
  parts::write_multirate(o.out, o.scenes_dir, o.progress);
  const std::string md = report_markdown(o, timing, duration);
  write_text(o.out / "report.md", md);
  return md;
}

} // namespace vtb::reproduction
