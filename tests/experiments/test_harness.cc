// The harness: error metrics on synthetic trajectories, compare end to end, the sweep's
// explicit stability boundary.
#include "support/fresh_dir.hh"
#include "support/small_models.hh"
#include "vtb/harness/compare.hh"
#include "vtb/harness/csv_table.hh"
#include "vtb/harness/ranks.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/harness/study.hh"
#include "vtb/harness/sweep.hh"
#include "vtb/problem/solver_registry.hh"
#include "vtb/reproduction/bench_scale.hh"
#include "vtb/solvers/explicit_euler.hh"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>

namespace vtb {
namespace {

Trajectory<2> synthetic(const std::vector<double>& t, double amplitude, double offset) {
  Trajectory<2> tr;
  for (double s : t) {
    tr.t.push_back(s);
    Nodal<2> f(2, 3);
    f << amplitude * s, 0, offset, 0, 0, amplitude * s;
    tr.field.push_back(f);
    tr.probe_u.push_back({Vec<2>(amplitude * s, 0.0)});
    tr.reaction.push_back({Vec<2>(-amplitude * s, offset)});
  }
  return tr;
}

TEST(Metrics, KnownErrorsOnSyntheticTrajectories) {
  // Reference field: two entries a t (a = 2) -> norm sqrt(2) a t, max sqrt(2) a at t = 1.
  // The run adds a constant 0.1 to one entry: e(t) = 0.1 / (sqrt(2) a) at every t.
  const std::vector<double> t = {0.0, 0.5, 1.0};
  const Trajectory<2> ref = synthetic(t, 2.0, 0.0), run = synthetic(t, 2.0, 0.1);
  const harness::ErrorMetrics m = harness::compare(run, ref);
  EXPECT_NEAR(m.displacement_max, 0.1 / (std::sqrt(2.0) * 2.0), 1e-15);
  EXPECT_NEAR(m.displacement_final, 0.1 / (std::sqrt(2.0) * 2.0), 1e-15);
  EXPECT_EQ(m.probe_max, 0.0);
  EXPECT_NEAR(m.reaction_max, 0.1 / 2.0, 1e-15);
  EXPECT_EQ(m.compared, 3u);
  // A run twice as large: error |a t| / (sqrt 2 a) per time, max 1 at t = 1.
  EXPECT_NEAR(harness::compare(synthetic(t, 4.0, 0.0), ref).displacement_max, 1.0, 1e-15);
  // Mismatched sample times are refused.
  EXPECT_THROW(harness::compare(synthetic({0.0, 0.6, 1.0}, 2.0, 0.0), ref), std::invalid_argument);
}

TEST(Compare, RunsTheDecompositionOnASmallPlate) {
  // Lloyd's springs, named: the model error below is their lattice theory's (the default
  // "auto" fits them to the FEM).
  const Scene scene = parse_scene(test::pulled_plate(8, 2, R"(
[solver]
dt = 0.01
springs = "lloyd"
)"),
                                  "plate.toml", ".");
  Scene s = scene;
  s.duration = 0.2;
  s.output_interval = 0.02;
  const auto res = harness::run_compare(s, {"filtered-full", "implicit-euler", "cvode"}, "fem");
  ASSERT_EQ(res.rows.size(), 4u);
  ASSERT_EQ(res.decomposition.size(), 3u);
  for (const auto& row : res.rows) {
    EXPECT_TRUE(row.report.stable) << row.solver;
    std::cout << row.solver << ": max " << row.error.displacement_max << ", final " << row.error.displacement_final
              << ", probe " << row.error.probe_max << "\n";
  }
  // The reference against itself is exact.
  EXPECT_EQ(res.rows.back().error.displacement_max, 0.0);
  // Model error: Lloyd's springs on this union-jack lattice are E_eff / E = 1.305 stiff in
  // uniaxial tension (lattice theory; test_integrators measures it), so a field scaled by
  // 1 / 1.305 is off by 1 - 1 / 1.305 = 0.234 in relative L2. Both models creep with the same
  // tau, so the ratio holds at every time up to inertia (t / tau = 4: the transient is gone).
  // The clamp's boundary layer, within about one width W of it (W / L = 1/4 of the strip)
  // where the lateral strain departs from nu times the axial one, shifts it by at most
  // ~ (W / L) nu 0.234 = 0.02.
  const double lattice = 1 - 1 / 1.305;
  EXPECT_NEAR(res.rows[2].error.displacement_final, lattice, 0.02) << "cvode vs fem";
  EXPECT_NEAR(res.rows[0].error.displacement_final, lattice, 0.02) << "filtered vs fem";
  EXPECT_NEAR(res.rows[1].error.displacement_final, lattice, 0.02) << "implicit Euler vs fem";
  // The decomposition's three terms are present, in order. The time error (filtered vs
  // cvode) is first order in dt. With c = tau k every mode creeps alike in the quasi-static
  // limit, x = F/k (1 - exp(-t/tau)), and backward Euler's error on that is
  // dt/(2 tau) (t/tau) exp(-t/tau) F/k (1 + O(dt/tau)): at t/tau = 4 (dt = 0.01, tau = 0.05)
  // 0.0073 of the final displacement, which we allow with the factor 1 + dt/tau.
  const double creep_bound = 0.01 / (2 * 0.05) * 4 * std::exp(-4.0) * (1 + 0.01 / 0.05);
  EXPECT_GT(res.decomposition[0].error.displacement_final, 0.0);
  EXPECT_LT(res.decomposition[0].error.displacement_final, creep_bound);
  std::cout << "filtered vs cvode: max " << res.decomposition[0].error.displacement_max << ", final "
            << res.decomposition[0].error.displacement_final << "\n";
  EXPECT_EQ(res.decomposition[1].a, "cvode");
  EXPECT_EQ(res.decomposition[1].b, "fem");
}

TEST(Compare, KeepsEachSolversRunOutputsAndFrames) {
  Scene s = parse_scene(test::pulled_plate(4, 2, R"(
[[probe]]
name = "tip"
point = [0.2, 0.0]
[solver]
dt = 0.01
)"),
                        "plate.toml", ".");
  s.duration = 0.1;
  s.output_interval = 0.03; // samples at 0, 0.03, 0.06, 0.09 and the last at 0.1
  const test::FreshDir dir;
  const auto res = harness::run_compare(s, {"filtered-full", "cvode"}, "fem", 0, nullptr, {dir.path(), true});
  ASSERT_EQ(res.rows.size(), 3u);
  for (const char* solver : {"filtered-full", "cvode", "fem"}) {
    const auto run = dir / solver;
    for (const char* f : {"probes.csv", "reactions.csv", "summary.json", "frames.pvd", "frames/frame_0004.vtu"})
      EXPECT_TRUE(std::filesystem::exists(run / f)) << solver << "/" << f;
    EXPECT_FALSE(std::filesystem::exists(run / "frames/frame_0005.vtu")) << solver << ": five samples, five frames";
    std::ifstream probes(run / "probes.csv");
    std::string line, last;
    int rows = 0;
    std::getline(probes, line);
    EXPECT_EQ(line, "t,probe,ux,uy,uz");
    while (std::getline(probes, line)) {
      ++rows;
      last = line;
    }
    EXPECT_EQ(rows, 5) << solver << ": one probe at five sample times";
    EXPECT_EQ(last.substr(0, last.find(',')), "0.1") << solver << ": the last sample is at the duration";
  }
}

TEST(Sweep, FindsTheExplicitBoundaryWhereThePredictionPutsIt) {
  // Undamped tiny plate: symplectic Euler on the linearised model is stable iff
  // dt < 2 / omega_max, and max_omega_squared is the exact largest eigenvalue, so the limit is
  // exact up to the geometric nonlinearity at the perturbation's 1e-6 amplitude (relative
  // ~1e-6). On a 2 % grid the boundary must fall between the two grid points around it:
  // 0.98 x stable and 1.02 x unstable. At 1.02 x the unstable mode grows by 1.49 per step
  // (|lambda| of lambda^2 - (2 - h^2) lambda + 1 = 0, h = 2.04), so the 2000 steps take any
  // round-off seed past the 1000 % strain criterion; at 0.98 x every mode is bounded.
  Scene s = parse_scene(test::plate_scene(4, 1, "[[fix]]\ngroup = \"left\"\n", 0.0), "tiny.toml", ".");
  s.duration = 0.2;
  s.output_interval = 0.01;
  const Model<2> model = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  const double predicted = explicit_critical_dt(max_omega_squared(model, true), 0.0, 0.0);
  s.initial_velocity = Eigen::Vector2d(1e-6, 1e-6);
  s.duration = 2000 * predicted;
  s.output_interval = s.duration / 20;
  std::vector<double> dts;
  for (int k = -5; k <= 5; ++k)
    if (k != 0) dts.push_back((1.0 + 0.02 * k) * predicted);
  const auto cells = harness::run_sweep(s, dts, {1.0}, {"explicit"});
  ASSERT_EQ(cells.size(), dts.size());
  for (const auto& c : cells) EXPECT_EQ(c.stable, c.dt < predicted) << "dt / predicted = " << c.dt / predicted;
  EXPECT_NEAR(cells.front().courant_dt, predicted, 1e-9 * predicted);
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(SolverRegistry, EveryEntryRunsAndUnknownNamesGetTheNearest) {
  // Every registered solver runs through the harness's one call (its factory), on a small
  // plate, to the end, recording every sample: a solver added to the table without a way to
  // run it fails here.
  Scene s = parse_scene(test::pulled_plate(4, 2, R"(
[solver]
dt = 1e-3
)"),
                        "plate.toml", ".");
  s.duration = 0.02;
  s.output_interval = 0.01;
  const Model<2> model = build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
  for (const auto& e : solvers::kEntries) {
    Trajectory<2> tr;
    const RunReport r = harness::run_solver(s, model, e.name, 0, tr);
    EXPECT_TRUE(r.stable) << e.name;
    EXPECT_EQ(tr.t.size(), 3u) << e.name;
    EXPECT_EQ(std::string(r.solver), e.name) << "the report names the registry entry";
  }
  try {
    solvers::find("implicit-eular", "--solvers");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(
                  "--solvers: unknown solver \"implicit-eular\"; did you mean \"implicit-euler\"?", 0),
              0u)
        << e.what();
  }
  // The scene parser reads the same table for [solver].kind, and suggests the nearest.
  try {
    parse_scene(test::plate_scene(4, 2, "[solver]\nkind = \"filterd\"\n"), "k.toml", ".");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean \"filtered\"?"), std::string::npos) << e.what();
  }
}

TEST(Sampling, EverySolverRecordsAtTheScenesSampleTimesWhateverItsStep) {
  // A user's study: output every 5 ms, steps of 20 ms (four samples per step) or of 3 ms (steps
  // that straddle the samples), duration 0.1 s. Every solver's samples are at 0, 0.005, ...,
  // 0.1 exactly (the last at the duration), so compare measures them against each other
  // instead of refusing (it used to exit 70: "sample 1 is at t = 0.02 in one run and 0.005 in
  // the reference").
  const std::vector<double> odd = sample_times(1.0, 0.3), expect = {0.0, 0.3, 0.6, 0.9, 1.0};
  ASSERT_EQ(odd.size(), expect.size());
  for (std::size_t k = 0; k < odd.size(); ++k) EXPECT_NEAR(odd[k], expect[k], 1e-15);
  EXPECT_EQ(odd.back(), 1.0) << "the last sample is at the duration exactly";
  EXPECT_EQ(sample_times(0.1, 0.05).size(), 3u);
  // Lloyd's springs, named: the 10 % bound on the time error below was sized on them (the
  // fitted plate creeps further, and at dt = 20 ms reached 10.9 %).
  Scene s = parse_scene(test::pulled_plate(8, 2, R"(
[solver]
springs = "lloyd"
)"),
                        "plate.toml", ".");
  s.duration = 0.1;
  s.output_interval = 0.005;
  const std::vector<double> times = sample_times(0.1, 0.005);
  ASSERT_EQ(times.size(), 21u);
  for (double dt : {0.02, 3e-3}) {
    const auto res = harness::run_compare(s, {"filtered-full", "implicit-euler", "fem"}, "cvode", dt);
    ASSERT_EQ(res.rows.size(), 4u);
    for (const auto& row : res.rows) {
      EXPECT_TRUE(row.report.stable) << row.solver;
      EXPECT_EQ(row.error.compared, times.size()) << row.solver << " at dt = " << dt;
      // Interpolating a first-order run within its step adds at most the step's own O(dt)
      // error: the spring runs stay within their time error of cvode, far below 100 %.
      if (row.solver != "fem") {
        EXPECT_LT(row.error.displacement_final, 0.1) << row.solver << " at dt = " << dt;
      }
    }
  }
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(Harness, NumbersThatCannotMislead) {
  Scene s = parse_scene(
      test::plate_scene(8, 2, "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.2, 0.0]\n"),
      "plate.toml", ".");
  s.duration = 0.1;
  s.output_interval = 0.01;
  // A sweep of cvode's dt would integrate the same run at every dt (error 0): refused.
  EXPECT_THROW(harness::run_sweep(s, {1e-3}, {1.0}, {"cvode"}), InputError);
  // An unstable row prints no real-time factor and says why it failed.
  const auto res = harness::run_compare(s, {"explicit", "implicit-euler"}, "cvode", 0.01);
  ASSERT_FALSE(res.rows[0].report.stable);
  const std::string table = harness::format_compare(res);
  EXPECT_NE(table.find("explicit: unstable ("), std::string::npos) << table;
  const std::string first =
      table.substr(table.find("\nexplicit"), table.find('\n', table.find("\nexplicit") + 1) - table.find("\nexplicit"));
  EXPECT_EQ(first.back(), '-') << first;
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

TEST(Study, ParetoFrontKeepsTheRunsNoOtherBeatsInBothErrorAndCost) {
  std::vector<harness::StudyRow> rows(5);
  const double err[] = {0.1, 0.05, 0.2, 0.01, 0.3}, cost[] = {1.0, 2.0, 3.0, 10.0, 0.5};
  for (int k = 0; k < 5; ++k) {
    rows[static_cast<std::size_t>(k)].error_all = err[k];
    rows[static_cast<std::size_t>(k)].cost = cost[k];
  }
  rows[4].stable = false; // cheapest, but unstable: never on the front
  harness::mark_pareto(rows);
  EXPECT_TRUE(rows[0].pareto);
  EXPECT_TRUE(rows[1].pareto);
  EXPECT_FALSE(rows[2].pareto) << "beaten by run 0 in both";
  EXPECT_TRUE(rows[3].pareto);
  EXPECT_FALSE(rows[4].pareto);
}

/// A 16-cell plate pulled at its right end, with a probe at the tip (the studies' scene).
Scene small_study_plate() {
  return parse_scene(test::pulled_plate(8, 2, R"(
[[probe]]
name = "tip"
point = [0.2, 0.025]
[solver]
dt = 2e-3
)",
                                        "0.2, 0.1"),
                     "plate.toml", ".");
}

/// A quick study of the full filter, implicit Euler and CVODE against CVODE's exact trajectory.
harness::StudyOptions quick_study_against_cvode() {
  harness::StudyOptions o;
  o.solvers = {"filtered-full", "implicit-euler", "cvode"};
  o.reference = "cvode";
  o.quick = true;
  return o;
}

TEST(Study, LaddersAgainstCvodeShowFirstOrderAndWriteTheirFiles) {
  // A quick study of a small plate against CVODE (the spring model's exact trajectory):
  // implicit Euler's error falls with dt at first order (the quick ladder divides dt by 4
  // each time: a ratio of 4 (1 + O(dt/T)), asserted above 3), every row is measured against
  // the same samples, and study.csv and study_plot.tex are written whole.
  Scene s = small_study_plate();
  s.duration = 0.2;
  s.output_interval = 0.02;
  harness::StudyOptions o = quick_study_against_cvode();
  const auto res = harness::run_study(s, o);
  ASSERT_EQ(res.rows.size(), 3u + 3u + 2u);
  std::vector<double> ie;
  for (const auto& r : res.rows) {
    EXPECT_TRUE(r.stable) << r.solver << " " << r.dt;
    if (r.solver == "implicit-euler") ie.push_back(r.error_all);
  }
  ASSERT_EQ(ie.size(), 3u);
  EXPECT_GT(ie[0] / ie[1], 3.0);
  EXPECT_GT(ie[1] / ie[2], 3.0);
  EXPECT_TRUE(std::any_of(res.rows.begin(), res.rows.end(), [](const auto& r) { return r.pareto; }));
  const test::FreshDir dir;
  std::string note;
  harness::write_study(res, dir.path(), note);
  std::ifstream csv(dir / "study.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("solver,dt,rtol,stable,error_all,error_probes", 0), 0u) << header;
  EXPECT_TRUE(std::filesystem::exists(dir / "study_plot.tex"));
  EXPECT_FALSE(std::filesystem::exists(dir / "study.csv.part"));
  // The plot is the paper's Pareto figure for the solvers this study ran, and those alone (a
  // series the study did not write, Bullet's here, would stop pdflatex).
  std::ifstream plot(dir / "study_plot.tex");
  const std::string tex((std::istreambuf_iterator<char>(plot)), std::istreambuf_iterator<char>());
  for (const char* name : {"filtered-full", "implicit-euler", "cvode"}) {
    EXPECT_NE(tex.find(std::string("\\addlegendentry{") + name + "}"), std::string::npos) << name << "\n" << tex;
    EXPECT_NE(tex.find(std::string("{data/acc_") + name + ".dat}"), std::string::npos) << name;
    EXPECT_TRUE(std::filesystem::exists(dir / "data" / (std::string("acc_") + name + ".dat"))) << name;
  }
  EXPECT_EQ(tex.find("bullet"), std::string::npos) << tex;
  // Drawn: LaTeX (scripts/setup.sh installs it) made the PNG, and no note says otherwise.
  EXPECT_TRUE(note.empty()) << note;
  EXPECT_GT(std::filesystem::file_size(dir / "study_plot.png"), 10000u);
  std::ifstream ie_series(dir / "data/acc_implicit-euler.dat");
  std::string line;
  int points = 0;
  while (std::getline(ie_series, line)) ++points;
  EXPECT_EQ(points, 1 + 3) << "header and the three stable implicit-Euler runs";
  EXPECT_TRUE(std::filesystem::exists(dir / "data/pareto.dat"));
}

TEST(Study, ShardsMergeIntoTheSerialStudy) {
  // A study split into two parts (--shard 0/2 and 1/2, each running its own reference) and
  // merged gives the serial study's rows: the same cells in the same order, and errors equal to
  // the bit (each cell is the same deterministic run measured against the same reference).
  // Timing columns, and so the Pareto marks, may differ. A missing or repeated part is refused.
  Scene s = small_study_plate();
  s.duration = 0.1;
  s.output_interval = 0.02;
  harness::StudyOptions o = quick_study_against_cvode();
  const auto serial = harness::run_study(s, o);
  const test::FreshDir dir;
  std::string note;
  for (int k = 0; k < 2; ++k) {
    o.shard = harness::parse_shard(std::to_string(k) + "/2");
    const auto part = harness::run_study(s, o);
    EXPECT_LT(part.rows.size(), serial.rows.size()) << "a part runs some of the cells";
    harness::write_study(part, dir / ("part" + std::to_string(k)), note);
  }
  const auto merged = harness::merge_studies({dir / "part1", dir / "part0"});
  ASSERT_EQ(merged.rows.size(), serial.rows.size());
  for (std::size_t i = 0; i < serial.rows.size(); ++i) {
    const auto &a = serial.rows[i], &b = merged.rows[i];
    EXPECT_EQ(a.solver, b.solver);
    EXPECT_EQ(a.dt, b.dt);
    EXPECT_EQ(a.rtol, b.rtol);
    EXPECT_EQ(a.stable, b.stable);
    EXPECT_EQ(a.error_all, b.error_all) << a.solver << " " << a.dt;
    EXPECT_EQ(a.error_probes, b.error_probes) << a.solver << " " << a.dt;
  }
  harness::write_study(merged, dir / "merged", note);
  EXPECT_TRUE(std::filesystem::exists(dir / "merged/study.csv"));
  EXPECT_THROW(harness::merge_studies({dir / "part0"}), InputError) << "part 1 of 2 is missing";
  EXPECT_THROW(harness::merge_studies({dir / "part0", dir / "part0"}), InputError) << "part 0 twice";
  EXPECT_THROW(harness::parse_shard("2/2"), InputError);
  EXPECT_THROW(harness::parse_shard("1"), InputError);
}

TEST(Study, SplitByCostBalancesTheParts) {
  // Longest first to the least loaded part: {5, 4, 3, 3, 2, 1} into 2 parts gives loads 9 and 9.
  const std::vector<double> cost = {3, 5, 1, 4, 2, 3};
  const std::vector<int> part = harness::split_by_cost(cost, 2);
  double load[2] = {0, 0};
  for (std::size_t i = 0; i < cost.size(); ++i) load[part[i]] += cost[i];
  EXPECT_EQ(load[0], 9.0);
  EXPECT_EQ(load[1], 9.0);
  EXPECT_EQ(part[1], 0) << "the costliest cell goes to the first part";
}

TEST(BenchScale, FitsTheExponentOfEachCostAgainstNodes) {
  // A ladder whose costs are exact powers of the node count (step ~ n^1.5, precompute ~ n,
  // heap ~ n^1.25) must give those exponents back (a least-squares line through exact points,
  // to round-off), per dimension and solver.
  const test::FreshDir dir;
  std::ofstream f(dir / "scaling.csv");
  f << "family,dim,nodes,springs,solver,precompute_ms,step_median_us,heap_mb\n";
  for (double n : {100.0, 400.0, 1600.0})
    for (const char* solver : {"filtered-full", "implicit-euler"})
      f << "box,3," << n << ",0," << solver << ',' << 2 * n << ',' << std::pow(n, 1.5) << ',' << std::pow(n, 1.25)
        << '\n';
  f.close();
  const harness::CsvTable fit = harness::CsvTable::parse(reproduction::scaling_fit(dir.path()), "scaling_fit.csv");
  ASSERT_EQ(fit.rows(), 2u);
  for (std::size_t r = 0; r < fit.rows(); ++r) {
    EXPECT_NEAR(fit.number(r, "step_exponent"), 1.5, 1e-3); // printed to 4 digits
    EXPECT_NEAR(fit.number(r, "precompute_exponent"), 1.0, 1e-3);
    EXPECT_NEAR(fit.number(r, "heap_exponent"), 1.25, 1e-3);
    EXPECT_EQ(fit.number(r, "nodes_max"), 1600.0);
  }
}

} // namespace
} // namespace vtb
