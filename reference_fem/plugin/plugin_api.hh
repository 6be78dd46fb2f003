#pragma once
// The boundary between vtb and its deal.II reference: the functions of vtb/fem/*.hh that need
// deal.II, as one table of pointers that the FEM plugin (plugin.cc, a module holding vtb_fem
// and linking deal.II) hands out and the client (client.cc) calls. deal.II, with the PETSc,
// Trilinos, HDF5 and OpenCASCADE it links, is 100 MB of a process's memory once loaded, so a
// process loads it only when a FEM runs (docs/architecture.md, "Modules loaded on demand").
#include "vtb/fem/continuum.hh"
#include "vtb/fem/kelvin_voigt.hh"

namespace vtb::fem::plugin {

/// Raised when the table's layout changes; the client refuses a plugin of another version.
inline constexpr int kApiVersion = 1;

struct Api {
  int version = kApiVersion;
  RunReport (*simulate2)(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&, bool);
  RunReport (*simulate3)(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&, bool);
  RunReport (*simulate_distributed2)(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&, bool);
  RunReport (*simulate_distributed3)(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&, bool);
  std::optional<ContinuumAnswers> (*continuum_answers2)(const Problem<2>&, const MaterialDesc&, const Eigen::MatrixXd&,
                                                        const ContinuumOptions&);
  std::optional<ContinuumAnswers> (*continuum_answers3)(const Problem<3>&, const MaterialDesc&, const Eigen::MatrixXd&,
                                                        const ContinuumOptions&);
  std::optional<ContinuumAnswer<2>> (*continuum_static2)(const Problem<2>&, const MaterialDesc&,
                                                         const ContinuumOptions&);
  std::optional<ContinuumAnswer<3>> (*continuum_static3)(const Problem<3>&, const MaterialDesc&,
                                                         const ContinuumOptions&);
  RunReport (*run_scene)(const Scene&, const std::filesystem::path&, bool, RunTables*);
  /// MPI through deal.II (MPI_InitFinalize): begin returns what end takes.
  void* (*mpi_begin)(int& argc, char**& argv);
  void (*mpi_end)(void*);
};

/// The plugin's one exported symbol.
inline constexpr const char* kEntryPoint = "vtb_fem_plugin_api";
using EntryPoint = const Api* (*)();

} // namespace vtb::fem::plugin
