#pragma once
/// \file
/// `vtb reproduce`: the paper's experiment and timing table on the 517- and 123-node plates,
/// the Fig. 3 analogue, accuracy against speed, the stability map, and a markdown report.

#include <filesystem>
#include <iosfwd>
#include <string>

namespace vtb::reproduction {

/// The figures report.md shows, as scripts/build_paper.sh draws them from paper/figures/FILE.tex
/// into figures/FILE.png beside it (a test checks that each has its .tex).
struct ReportFigure {
  const char* file;
  const char* title;
};
inline constexpr ReportFigure kReportFigures[] = {
    {"fig3", "The plate at three times, coloured by strain (the paper's Fig. 3)"},
    {"accuracy_speed", "Accuracy against speed, Pareto front marked"},
    {"stability", "Stability over time step and stiffness"},
    {"decomposition", "Error decomposition: time integration, model, total"},
    {"convergence", "Convergence of implicit Euler and CVODE"},
    {"creep", "Creep against the Kelvin-Voigt law"},
    {"scaling", "Step time and memory against nodes"},
    {"haptics", "The haptic loop: servo periods and a physics stall"},
    {"tip_force", "The held force against depth: the tool tip on two meshes, a point proxy, the half-space"},
    {"multirate", "A 10k-node body felt in real time: the multirate session against lockstep at 1 kHz"},
    {"deep_press", "A deep press: the springs against the neo-Hookean, linear and St. Venant-Kirchhoff continua"},
};

struct ReproduceOptions {
  bool quick = false;               ///< 2 s of simulated time instead of 10, smaller ladders
  std::filesystem::path out;        ///< output folder
  std::filesystem::path scenes_dir; ///< where plate517_step.toml etc. live
  std::ostream* progress = nullptr;
};

/// Writes timing_table.csv, fig3/*.csv|vtu, accuracy_speed.csv, stability.csv,
/// decomposition.csv, creep.csv, scaling.csv, haptics_*.csv, meta.csv and report.md into
/// options.out; returns the report's text.
std::string run_reproduce(const ReproduceOptions& options);

} // namespace vtb::reproduction
