#include "vtb/harness/study.hh"
#include "study_json.hh"
#include "vtb/harness/tex.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/fem/continuum.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/metrics.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/problem/output.hh"
#include "vtb/solvers/cvode_solver.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <numeric>
#include <optional>
#include <sstream>

namespace vtb::harness {

std::vector<std::string> default_study_solvers(int dim) {
  std::vector<std::string> names;
  for (const solvers::Entry& e : solvers::kEntries)
    if (e.springs && e.fixed_step && *e.filter &&
        (dim == 3 || (std::string_view(e.filter) != solvers::kFilterMultigrid &&
                      std::string_view(e.filter) != solvers::kFilterTensorMultigrid)))
      names.emplace_back(e.name);
  for (const char* s : {solvers::kImplicitEuler, solvers::kExplicit, solvers::kCvode}) names.emplace_back(s);
  return names;
}

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

/// A reference run's progress on `log` (`what` names the run): a line at every tenth of the duration with the time it
/// has taken and the estimate of what remains (at the rate of the steps since the first, whose
/// time holds the set-up).
std::function<void(double)> progress_printer(std::ostream* log, const char* what) {
  if (!log) return {};
  using clock = std::chrono::steady_clock;
  return [log, what, start = clock::now(), first = clock::time_point(), first_done = 0.0,
          next = 0.1](double done) mutable {
    const auto now = clock::now();
    if (first_done == 0) {
      first = now;
      first_done = done;
    }
    if (done + 1e-12 < next) return;
    const double s = std::chrono::duration<double>(now - start).count();
    const double rate =
        done > first_done ? std::chrono::duration<double>(now - first).count() / (done - first_done) : 0;
    *log << "    " << what << " " << std::lround(100 * done) << " %: " << std::lround(s) << " s, ~"
         << std::lround(rate * (1 - done)) << " s to go\n"
         << std::flush;
    while (next <= done + 1e-12) next += 0.1;
  };
}

} // namespace

template <int dim>
ReferenceStep fem_reference_in_time(const Scene& scene, const Problem<dim>& problem, int refinements, double tolerance,
                                    Trajectory<dim>& out, std::ostream* log, bool distributed) {
  fem::FemOptions f = fem::options_from(scene.solver);
  f.degree = 2;
  f.refinements = refinements;
  f.static_solve = false;
  const auto run = [&](double dt, Trajectory<dim>& tr, const char* what) {
    f.dt = dt;
    f.progress = progress_printer(log, what);
    if (log)
      *log << "  " << what << ": " << std::lround(problem.duration / dt) << " steps at dt = " << dt << " s ...\n"
           << std::flush;
    tr = Trajectory<dim>();
    const RunReport r = distributed ? fem::simulate_distributed<dim>(problem, scene.material, f, tr, true)
                                    : fem::simulate<dim>(problem, scene.material, f, tr, true);
    if (!r.stable) throw std::runtime_error("vtb study: the reference run failed: " + r.failure);
  };
  const double dt = scene.solver.dt;
  Trajectory<dim> at4, at2;
  run(4 * dt, at4, "reference at 4 dt (for the time error's estimate)");
  run(2 * dt, at2, "reference at 2 dt (for the time error's estimate)");
  run(dt, out, "reference at dt");
  // Differences d(h) = u(2h) - u(h) ~ C (2^p - 1) h^p: their ratio is 2^p, and the error at dt
  // is d(dt) / (2^p - 1). The order is clamped to [1, 2]: the scheme's own, or less where the
  // loads switch on as steps (then the start is inconsistent and the transient first order).
  const double d4 = compare(at4, at2).displacement_max, d2 = compare(at2, out).displacement_max;
  const double p = d2 > 0 && d4 > 0 ? std::clamp(std::log2(d4 / d2), 1.0, 2.0) : 2.0;
  ReferenceStep r;
  r.dt = dt;
  r.order = p;
  r.error = d2 / (std::pow(2.0, p) - 1);
  int halvings = 0;
  while (halvings < 2 && !(r.error / std::pow(2.0, p * halvings) <= tolerance)) ++halvings;
  std::ostringstream how;
  how << std::setprecision(2) << "time error at dt ~" << 100 * r.error << " % (P2 at 4 dt, 2 dt and dt: order " << p;
  if (halvings > 0) {
    r.dt = dt / std::pow(2.0, halvings);
    r.error /= std::pow(2.0, p * halvings);
    how << "; at dt/" << (1 << halvings) << " ~" << 100 * r.error << " %";
    run(r.dt, out, "reference at the smaller step");
  }
  how << "; allowed " << 100 * tolerance << " %)";
  r.how = how.str();
  return r;
}

template ReferenceStep fem_reference_in_time<2>(const Scene&, const Problem<2>&, int, double, Trajectory<2>&,
                                                std::ostream*, bool);
template ReferenceStep fem_reference_in_time<3>(const Scene&, const Problem<3>&, int, double, Trajectory<3>&,
                                                std::ostream*, bool);

namespace {

/// The reference, converged at its own step: the continuum (P2 at the coarsest refinement whose
/// static answer to the scene's final loads and drives is within 1 % of the next one's, by the
/// ladder of vtb/fem/continuum.hh within its budget of dofs, converged in time by fem_reference_in_time), or the
/// spring model's exact trajectory (CVODE at rtol 1e-10). Returns what it was; `log` is told the
/// reference's level, dofs and steps before it runs, and its progress while it runs.
/// With `distributed` (under mpirun, every rank calling) the FEM runs over all the ranks
/// (deal.II's distributed path), each ending with the whole trajectory.
template <int dim>
std::string reference_run(const Scene& scene, const Model<dim>& model, const std::string& reference,
                          Trajectory<dim>& ref, std::ostream* log, bool distributed, KeptLadders* kept) {
  std::string note;
  if (reference == solvers::kFem) {
    fem::FemOptions f = fem::options_from(scene.solver);
    f.degree = 2;
    fem::ContinuumOptions c;
    c.drives_displaced = true;
    bool reused = false;
    const auto ladder = static_ladder<dim>(model, scene.material, c, kept, &reused);
    const int refinements = ladder ? ladder->sufficient_refinements : 0;
    const std::string level = "P2 refined " + std::to_string(refinements) + "x";
    const std::string why =
        ladder ? std::string(reused ? "static ladder, the springs' load check's: " : "static ladder: ") + ladder->how
               : "P2 on the mesh is above the ladder's budget of dofs: run unchecked";
    if (log) *log << "reference: fem, " << level << " (" << why << ")\n" << std::flush;
    const ReferenceStep step =
        fem_reference_in_time<dim>(scene, model, refinements, c.tolerance, ref, log, distributed);
    note = "fem, " + level + " (" + why + "), generalized-alpha, dt = " + std::to_string(step.dt) + " s (" + step.how +
           ")" + (distributed ? ", over " + std::to_string(world().size) + " ranks" : "");
  } else if (reference == solvers::kCvode) {
    const RunReport rr = simulate_cvode(model, CvodeOptions{1e-10, 1e-14}, ref, true);
    if (!rr.stable) throw std::runtime_error("vtb study: the reference run failed: " + rr.failure);
    note = "cvode, rtol 1e-10, atol 1e-14";
  } else {
    throw InputError("vtb study: --reference must be fem or cvode, not \"" + reference + "\"");
  }
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

/// One cell of a study: a solver at one step, or CVODE at one tolerance, in the serial order.
struct Cell {
  std::string solver;
  double dt = 0, rtol = 0;
  double steps = 0, budget = 0; ///< skipped when steps > budget
  double cost = 0;              ///< estimated: steps x nodes (x 8 for a factor or CVODE's Newton)
};

template <int dim> std::vector<Cell> study_cells(const Scene& scene, const Model<dim>& model, const StudyOptions& o) {
  std::vector<Cell> cells;
  const double n = model.num_nodes(), scene_steps = model.duration / scene.solver.dt;
  for (const auto& solver : o.solvers.empty() ? default_study_solvers(dim) : o.solvers) {
    if (solver == solvers::kCvode) {
      for (double rtol : rtol_ladder(o.quick))
        cells.push_back({solver, 0, rtol, 0, 0, 8 * n * scene_steps * std::cbrt(1e-3 / rtol)});
      continue;
    }
    for (double dt : solver_dts(scene, model, solver, o.quick)) {
      const double steps = model.duration / dt, budget = o.quick ? 2e5 : 2e6;
      const double factor = solver == solvers::kImplicitEuler ? 8 : 1;
      cells.push_back({solver, dt, 0, steps, budget, steps > budget ? 0 : factor * steps * n});
    }
  }
  return cells;
}

/// A run's trajectory as doubles (what compare() reads: times, probes, reactions, fields), so
/// that rank 0 can send the reference to the others.
template <int dim> std::vector<double> pack(const Trajectory<dim>& tr) {
  const std::size_t samples = tr.t.size(), probes = samples ? tr.probe_u[0].size() : 0,
                    supports = samples && !tr.reaction.empty() ? tr.reaction[0].size() : 0,
                    nodes = tr.field.empty() ? 0 : static_cast<std::size_t>(tr.field[0].cols());
  std::vector<double> v = {double(samples), double(probes), double(supports), double(nodes)};
  for (std::size_t k = 0; k < samples; ++k) {
    v.push_back(tr.t[k]);
    for (const auto& p : tr.probe_u[k]) v.insert(v.end(), p.data(), p.data() + dim);
    if (supports)
      for (const auto& r : tr.reaction[k]) v.insert(v.end(), r.data(), r.data() + dim);
    if (nodes) v.insert(v.end(), tr.field[k].data(), tr.field[k].data() + dim * nodes);
  }
  return v;
}

template <int dim> Trajectory<dim> unpack(const std::vector<double>& v) {
  Trajectory<dim> tr;
  const auto samples = static_cast<std::size_t>(v[0]), probes = static_cast<std::size_t>(v[1]),
             supports = static_cast<std::size_t>(v[2]);
  const auto nodes = static_cast<Eigen::Index>(v[3]);
  std::size_t at = 4;
  const auto vec = [&] {
    Vec<dim> x = Eigen::Map<const Vec<dim>>(v.data() + at);
    at += dim;
    return x;
  };
  for (std::size_t k = 0; k < samples; ++k) {
    tr.t.push_back(v[at++]);
    tr.probe_u.emplace_back();
    for (std::size_t p = 0; p < probes; ++p) tr.probe_u.back().push_back(vec());
    if (supports) {
      tr.reaction.emplace_back();
      for (std::size_t r = 0; r < supports; ++r) tr.reaction.back().push_back(vec());
    }
    if (nodes) {
      tr.field.push_back(Eigen::Map<const Nodal<dim>>(v.data() + at, dim, nodes));
      at += static_cast<std::size_t>(dim * nodes);
    }
  }
  return tr;
}

/// A cell's run, kept until the reference has arrived to measure it against.
template <int dim> struct Finished {
  StudyRow row;
  RunReport rep;
  Trajectory<dim> tr;
  double wall = 0;
};

template <int dim>
StudyResult study_impl(const Scene& scene, const Model<dim>& model, const StudyOptions& o, std::ostream* log,
                       KeptLadders* kept) {
  using clock = std::chrono::steady_clock;
  const Ranks w = world();
  const bool spread = w.size > 1 && !o.shard.active();
  StudyResult res;
  res.scene = scene.name;
  res.reference = o.reference;
  res.filter = chosen_filter(model, scene.solver.step.filter); // what `filtered` runs (auto resolved)
  res.nodes = model.num_nodes();
  res.duration = model.duration;
  res.shard = o.shard;
  const std::string where = binding(&res.timing_shared);
  if (!w.root() && !o.shard.active()) log = nullptr; // rank 0 alone prints
  const std::vector<Cell> cells = study_cells(scene, model, o);
  res.cells = static_cast<long>(cells.size());
  std::vector<double> costs;
  for (const Cell& c : cells) costs.push_back(c.cost);
  std::vector<std::size_t> order(cells.size()); // the queue's order: costliest first
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return costs[a] > costs[b]; });

  // Collectives in one order on every rank: the queue's window first, then the reference's
  // broadcast (posted here by the others, sent by rank 0 when it has the reference), then the
  // gather of the rows.
  // The reference: under MPI a FEM reference runs over all the ranks before the cells (on the
  // 517-node plate's quick study, P2 refined at dt / 4: 4.8 s on 2 ranks against 11.6 s on one,
  // where the cells take about 3 s in all); CVODE's, which does not distribute, runs on rank 0
  // while the others take cells.
  std::optional<CellQueue> queue;
  if (!o.shard.active()) queue.emplace(static_cast<long>(cells.size()));
  const bool distributed_ref = spread && o.reference == solvers::kFem;
  Trajectory<dim> ref;
  bool have_ref = false;
  std::optional<Broadcast> sent;
  if (spread && !distributed_ref) sent.emplace();
  if (w.root() || !spread || distributed_ref) {
    res.reference_note = reference_run(scene, model, o.reference, ref, log, distributed_ref, kept);
    have_ref = true;
    if (sent) sent->send(pack(ref));
    if (log) *log << "reference: " << res.reference_note << "\n";
  }
  std::vector<Finished<dim>> waiting;
  const auto measure = [&](Finished<dim>& f) {
    StudyRow row = measured_row(f.row, f.rep, f.tr, ref, f.wall, model.duration);
    if (log)
      *log << "  " << row.solver << (row.rtol > 0 ? " rtol " : " dt ") << (row.rtol > 0 ? row.rtol : row.dt)
           << (row.stable ? "" : " UNSTABLE") << ": error " << std::to_string(row.error_all) << ", "
           << std::to_string(row.total_seconds) << " s\n"
           << std::flush;
    res.rows.push_back(std::move(row));
  };
  const auto run_cell = [&](std::size_t i, long taken) {
    const Cell& c = cells[i];
    StudyRow row;
    row.cell = static_cast<long>(i);
    row.solver = c.solver;
    row.binding = where;
    if (log && spread) *log << "[" << taken + 1 << "/" << cells.size() << " cells taken across ranks]\n";
    if (c.rtol == 0 && c.steps > c.budget) {
      row = skipped_row(c.solver, c.dt, c.steps, c.budget);
      row.cell = static_cast<long>(i);
      row.binding = where;
      if (log) *log << "  " << row.solver << " dt " << row.dt << " " << row.failure << "\n" << std::flush;
      res.rows.push_back(std::move(row));
      return;
    }
    Finished<dim> f;
    const auto a = clock::now();
    if (c.rtol > 0) {
      row.rtol = c.rtol;
      f.rep = simulate_cvode(model, CvodeOptions{c.rtol, c.rtol * 1e-4}, f.tr, true);
    } else {
      row.dt = c.dt;
      f.rep = run_solver(scene, model, c.solver, c.dt, f.tr);
    }
    f.wall = std::chrono::duration<double>(clock::now() - a).count();
    f.row = std::move(row);
    if (!have_ref && sent->ready()) {
      ref = unpack<dim>(sent->data());
      have_ref = true;
    }
    waiting.push_back(std::move(f));
    if (have_ref) {
      for (auto& g : waiting) measure(g);
      waiting.clear();
    }
  };
  if (o.shard.active()) {
    const std::vector<int> part = split_by_cost(costs, o.shard.count);
    for (std::size_t k = 0; k < order.size(); ++k)
      if (part[order[k]] == o.shard.index) run_cell(order[k], static_cast<long>(k));
  } else {
    for (long k; (k = queue->next()) >= 0;) run_cell(order[static_cast<std::size_t>(k)], k);
  }
  if (!have_ref) {
    sent->wait();
    ref = unpack<dim>(sent->data());
  }
  for (auto& g : waiting) measure(g);
  if (spread) { // every row to rank 0, in the serial order there
    nlohmann::json mine = nlohmann::json::array();
    for (const auto& r : res.rows) mine.push_back(row_json(r));
    const std::vector<std::string> all = gather_on_root(mine.dump());
    if (w.root()) {
      res.rows.clear();
      for (const auto& text : all)
        for (const auto& j : nlohmann::json::parse(text)) res.rows.push_back(row_from_json(j));
    }
  }
  std::sort(res.rows.begin(), res.rows.end(), [](const StudyRow& a, const StudyRow& b) { return a.cell < b.cell; });
  mark_pareto(res.rows);
  return res;
}

} // namespace

StudyResult run_study(const Scene& scene_in, const StudyOptions& o, std::ostream* log) {
  for (const auto& solver : o.solvers) // before any run: a typo costs nothing
    if (!solvers::find(solver, "vtb study").springs)
      throw InputError("vtb study: solver \"" + solver + "\" is not one to study (" +
                       solvers::list(solvers::is_spring) + ")");
  if (o.reference != solvers::kFem && o.reference != solvers::kCvode) // before any rank waits for it
    throw InputError("vtb study: --reference must be fem or cvode, not \"" + o.reference + "\"");
  Scene scene = scene_in;
  if (o.quick && scene.duration > 1.0) { // a quick study looks at the first second
    scene.duration = 1.0;
    scene.output_interval = std::min(scene.output_interval, scene.duration);
  }
  KeptLadders kept;                                       // the load check's static ladder
  const Yardstick yardstick = continuum_yardstick(&kept); // the default springs, as vtb run builds them
  // A fit of seconds to minutes (3D) comes first: the log says how it advances.
  FitProgress progress;
  if (log)
    progress = [log, last = std::string()](const char* stage, int step, int steps) mutable {
      if (last != stage) *log << "springs: " << stage << (std::string(stage) == "done" ? "\n" : " ...\n");
      last = stage;
      if (std::string(stage) == "fit") *log << "  step " << step << " (at most " << steps << ")\n";
      *log << std::flush;
    };
  return with_model(
      scene,
      [&](const auto& model) {
        constexpr int dim = std::decay_t<decltype(model)>::dimension;
        return study_impl<dim>(scene, model, o, log, &kept);
      },
      progress, &yardstick);
}

} // namespace vtb::harness
