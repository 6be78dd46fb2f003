#include "vtb/reproduction/bench_scale.hh"

#include "reproduce_parts.hh"
#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"
#include "vtb/harness/csv_table.hh"
#include "vtb/problem/problem.hh"
#include "vtb/reproduction/paper_data.hh"
#include "vtb/springs/fitted_springs.hh"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>
#include <tuple>

namespace vtb::reproduction {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables

std::string fit_ladder(const std::vector<int>& slabs, std::ostream* log) {
  std::ostringstream os;
  os << "family,dim,nodes,springs,fit_seconds,lm_steps,validation_error,chosen\n";
  for (const int n : slabs) {
    if (log) *log << "[fit] CGAL slab of about " << n << " nodes\n";
    std::ostringstream scene;
    scene << "[scene]\nname = \"fit-ladder\"\nduration = 0.01\noutput_interval = 0.01\n[mesh]\ngenerate = { shape = "
             "\"box\", size = [0.2, 0.05, 0.05], mesher = \"cgal\", nodes = "
          << n << " }\n[material]\nyoung_modulus = 1.0\npoisson_ratio = 0.25\ndensity = 1.0\n[[fix]]\ngroup = "
          << "\"left\"\n[solver]\nkind = \"implicit-euler\"\ndt = 0.01\nsprings = \"lloyd\"\n";
    try {
      with_problem(parse_scene(scene.str(), "fit-ladder", "."), [&](const auto& problem) {
        FitOptions o; // the defaults springs = "fitted" runs, on the scene's supports
        for (int v = 0; v < problem.num_nodes(); ++v)
          if (problem.constrained[static_cast<std::size_t>(v)]) o.supports.push_back(v);
        FitReport rep;
        const auto a = std::chrono::steady_clock::now();
        const Eigen::VectorXd k = fitted_stiffness(problem.mesh, 1.0, 0.25, 1.0, o, &rep);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
        os << "cgal-slab," << problem.mesh.points.rows() << ',' << problem.num_nodes() << ',' << k.size() << ','
           << std::setprecision(4) << seconds << ',' << rep.iterations << ',' << rep.validation() << ',' << rep.chosen
           << '\n';
      });
    } catch (const InputError& e) { // a build without CGAL's meshers
      if (log) *log << "[fit] skipped: " << e.what() << "\n";
    }
  }
  return os.str();
}

std::string scaling_fit(const std::filesystem::path& dir) {
  const CsvTable t = CsvTable::read(dir / "scaling.csv");
  struct Series {
    std::vector<double> nodes, step, pre, heap;
  };
  std::map<std::tuple<std::string, std::string, std::string>, Series> series;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    Series& s = series[{t.text(r, "family"), t.text(r, "dim"), t.text(r, "solver")}];
    s.nodes.push_back(t.number(r, "nodes"));
    s.step.push_back(t.number(r, "step_median_us"));
    s.pre.push_back(t.number(r, "precompute_ms"));
    s.heap.push_back(t.number(r, "heap_mb"));
  }
  std::ostringstream os;
  os << std::setprecision(4)
     << "family,dim,solver,nodes_min,nodes_max,step_exponent,precompute_exponent,heap_exponent\n";
  for (const auto& [key, s] : series) {
    const auto [lo, hi] = std::minmax_element(s.nodes.begin(), s.nodes.end());
    os << std::get<0>(key) << ',' << std::get<1>(key) << ',' << std::get<2>(key) << ',' << *lo << ',' << *hi << ','
       << paper::loglog_slope(s.nodes, s.step) << ',' << paper::loglog_slope(s.nodes, s.pre) << ','
       << paper::loglog_slope(s.nodes, s.heap) << '\n';
  }
  return os.str();
}

void bench_scale(const std::filesystem::path& out, bool quick, std::ostream* progress, std::ostream& table) {
  parts::write_scaling(out, quick, progress);
  const std::string fit = scaling_fit(out);
  write_files_atomically(out, {{"scaling_fit.csv", fit}});
  const CsvTable t = CsvTable::read(out / "scaling.csv");
  table << std::left << std::setw(11) << "family" << std::setw(5) << "dim" << std::setw(8) << "nodes" << std::setw(18)
        << "solver" << std::right << std::setw(14) << "step (us)" << std::setw(16) << "precompute (ms)" << std::setw(12)
        << "heap (MB)" << std::setw(14) << "error vs fem\n";
  for (std::size_t r = 0; r < t.rows(); ++r)
    table << std::left << std::setw(11) << t.text(r, "family") << std::setw(5) << t.text(r, "dim") << std::setw(8)
          << t.text(r, "nodes") << std::setw(18) << t.text(r, "solver") << std::right << std::setw(14)
          << t.text(r, "step_median_us") << std::setw(16) << t.text(r, "precompute_ms") << std::setw(12)
          << t.text(r, "heap_mb") << std::setw(13) << t.text(r, "error_vs_fem") << "\n";
  table << "\nfitted exponents (cost ~ nodes^p), scaling_fit.csv:\n" << fit;
  const std::string springs =
      fit_ladder(quick ? std::vector<int>{2000} : std::vector<int>{1000, 2000, 5000, 10000}, progress);
  write_files_atomically(out, {{"spring_fit.csv", springs}});
  table << "\nthe spring fit (springs = \"fitted\", no cache), spring_fit.csv:\n" << springs;
}

} // namespace vtb::reproduction
