#include "commands.hh"

#include "vtb/reproduction/paper_data.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_paper_data(CLI::App& app) {
  struct Opts {
    std::string in = "out/reproduce", out = "out/paper/data";
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "paper-data", "Turn a reproduction's CSV files into the paper's data (numbers.tex, table rows, .dat series); "
                    "scripts/build_paper.sh runs it");
  cmd->add_option("reproduce_dir", o->in, "The folder vtb reproduce wrote (default: out/reproduce)");
  cmd->add_option("out_dir", o->out, "Where to write (default: out/paper/data)");
  return [o]() {
    reproduction::write_paper_data(o->in, o->out);
    std::cout << "paper data in " << o->out << "\n";
    return 0;
  };
}

} // namespace vtb::cli
