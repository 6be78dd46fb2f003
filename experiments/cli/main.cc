/// vtb: the Voigt deformation testbed command line (README.md, docs/scenes.md, docs/harness.md).
#include "commands.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/ranks.hh"

#include <cstdio>
#include <iostream>

int main(int argc, char** argv) {
  vtb::fem::MpiScope mpi(argc, argv); // only under mpirun
  // Under mpirun every rank parses the same command line; rank 0 alone prints (the output and
  // the one-line errors). study and sweep spread their cells over the ranks and run --solver
  // fem its mesh, reproduce its parts; every other command runs on rank 0 alone, so that each
  // prints and writes once.
  const vtb::harness::Ranks world = vtb::harness::world();
  if (!world.root()) {
    std::cout.setstate(std::ios::failbit);
    std::cerr.setstate(std::ios::failbit);
  }
  CLI::App app{"vtb: the Voigt deformation testbed (Cai, Dill, Payandeh mass-spring model and references)"};
  app.require_subcommand(1);
  vtb::cli::Action run = vtb::cli::add_run(app);
  vtb::cli::Action mesh = vtb::cli::add_mesh(app);
  vtb::cli::Action compare = vtb::cli::add_compare(app);
  vtb::cli::Action sweep = vtb::cli::add_sweep(app);
  vtb::cli::Action reproduce = vtb::cli::add_reproduce(app);
  vtb::cli::Action haptics = vtb::cli::add_haptics(app);
  vtb::cli::Action view = vtb::cli::add_view(app);
  vtb::cli::Action study = vtb::cli::add_study(app);
  vtb::cli::Action merge = vtb::cli::add_merge(app);
  vtb::cli::Action paper_data = vtb::cli::add_paper_data(app);
  vtb::cli::Action solver_list = vtb::cli::add_solvers(app);
  vtb::cli::Action bench = vtb::cli::add_bench(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!world.root() && !app.got_subcommand("run") && !app.got_subcommand("study") && !app.got_subcommand("sweep") &&
        !app.got_subcommand("reproduce"))
      return 0;
    if (app.got_subcommand("run")) return run();
    if (app.got_subcommand("mesh")) return mesh();
    if (app.got_subcommand("compare")) return compare();
    if (app.got_subcommand("sweep")) return sweep();
    if (app.got_subcommand("reproduce")) return reproduce();
    if (app.got_subcommand("haptics")) return haptics();
    if (app.got_subcommand("view")) return view();
    if (app.got_subcommand("study")) return study();
    if (app.got_subcommand("merge")) return merge();
    if (app.got_subcommand("paper-data")) return paper_data();
    if (app.got_subcommand("solvers")) return solver_list();
    if (app.got_subcommand("bench")) return bench();
  } catch (const vtb::InputError& e) {
    std::cerr << "vtb: error: " << e.what() << "\n";
    return 1;                       // every rank read the same input and stops here alike
  } catch (const vtb::IoError& e) { // the input was fine; the folder or the disk was not
    std::cerr << "vtb: I/O error: " << e.what() << "\n";
    return vtb::harness::end_all_ranks(74); // EX_IOERR (sysexits.h)
  } catch (const std::exception& e) {
    if (world.root())
      std::cerr << "vtb: internal error: " << e.what() << "\n";
    else
      std::fprintf(stderr, "vtb: internal error on rank %d: %s\n", world.rank, e.what()); // rank 0 may not see it
    return vtb::harness::end_all_ranks(70);
  }
  return 0;
}
