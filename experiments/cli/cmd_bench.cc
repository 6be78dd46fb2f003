#include "commands.hh"

#include "vtb/reproduction/bench_scale.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_bench(CLI::App& app) {
  struct Opts {
    std::string out = "out/bench-scale";
    bool quick = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks of the harness (Google Benchmark programs: vtb_bench_*)");
  bench->require_subcommand(1);
  CLI::App* scale = bench->add_subcommand(
      "scale", "Step time, precompute and heap of the spring solvers over a 2D and a 3D mesh ladder, with the fitted "
               "exponent of each cost against nodes (scaling.csv, scaling_fit.csv), and the spring fit's cost on CGAL "
               "slabs (spring_fit.csv)");
  scale->add_flag("--quick", o->quick, "The reproduction's small ladder (2D to 4,257 nodes, 3D to 1,225)");
  scale->add_option("--out", o->out, "Output folder (default: out/bench-scale)");
  return [o]() {
    reproduction::bench_scale(o->out, o->quick, &std::cerr, std::cout);
    return 0;
  };
}

} // namespace vtb::cli
