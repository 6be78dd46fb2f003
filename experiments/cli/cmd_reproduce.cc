#include "commands.hh"

#include "vtb/reproduction/reproduce.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

Action add_reproduce(CLI::App& app) {
  struct Opts {
    bool quick = false;
    std::string out = "out/reproduce";
    std::string scenes = VTB_SCENES_DIR;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "reproduce", "The paper's timing table on the 517- and 123-node plates, the Fig. 3 analogue, accuracy vs speed, "
                   "the stability map and report.md");
  cmd->add_flag("--quick", o->quick, "2 s of simulated time and small ladders (a few minutes)");
  cmd->add_option("--out", o->out, "Output folder (default: out/reproduce)");
  cmd->add_option("--scenes", o->scenes,
                  "Folder with plate517_step.toml, plate517_four_forces.toml, plate123_step.toml");
  return [o]() {
    reproduction::ReproduceOptions ro;
    ro.quick = o->quick;
    ro.out = o->out;
    ro.scenes_dir = o->scenes;
    ro.progress = &std::cerr;
    std::cout << reproduction::run_reproduce(ro) << "\noutputs in " << o->out << "\n";
    return 0;
  };
}

} // namespace vtb::cli
