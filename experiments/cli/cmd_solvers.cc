#include "commands.hh"

#include "vtb/problem/solver_registry.hh"

#include <cstdio>
#include <iostream>

namespace vtb::cli {

Action add_solvers(CLI::App& app) {
  app.add_subcommand("solvers", "List the registered solvers: name, what it is, the [solver] keys it reads");
  return [] {
    for (const auto& e : solvers::kEntries) {
      char line[512];
      std::snprintf(line, sizeof line, "%-20s %s\n%-20s [solver] keys: %s%s\n", e.name, e.description, "", e.keys,
                    e.scene_kind ? "" : " (harness name: not a [solver].kind)");
      std::cout << line;
    }
    return 0;
  };
}

} // namespace vtb::cli
