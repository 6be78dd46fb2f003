#pragma once
/// \file
/// The subcommands of the `vtb` CLI. Each registers its options on the app and returns
/// the function that runs it (exit code).

#include <CLI/CLI.hpp>

#include "vtb/harness/study.hh"

#include <filesystem>
#include <functional>

namespace vtb::cli {

using Action = std::function<int()>;

Action add_run(CLI::App& app);
Action add_mesh(CLI::App& app);
Action add_compare(CLI::App& app);
Action add_sweep(CLI::App& app);
Action add_reproduce(CLI::App& app);
Action add_haptics(CLI::App& app);
Action add_view(CLI::App& app);
Action add_study(CLI::App& app);
Action add_merge(CLI::App& app); ///< vtb merge: the parts of a sharded study joined
/// Writes a study's files into out and prints its table (vtb study, vtb merge).
int finish_study(const harness::StudyResult& result, const std::filesystem::path& out);
Action add_paper_data(CLI::App& app);
Action add_solvers(CLI::App& app);
Action add_bench(CLI::App& app);

/// `--kinematics` (run, compare, study): the FEM's law, overriding [solver].kinematics, into `into`.
void add_kinematics_option(CLI::App* cmd, std::string& into);

} // namespace vtb::cli
