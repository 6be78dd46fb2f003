#pragma once
/// \file
/// A module: a shared object that vtb loads on demand, so that a heavy dependency enters a
/// process only when a call needs it (the FEM reference with deal.II, docs/architecture.md; the
/// gmsh API, docs/meshes.md). It is looked for in ../lib beside the program (or the library)
/// that holds this code, then at the path the build wrote it to. Loaded with RTLD_NODELETE:
/// once in, it stays (deal.II's and OpenCASCADE's static state outlives a call, MPI cannot be
/// initialised twice), and a second load only finds it again.

#include <string>

namespace vtb {

class Module {
public:
  /// `file`: the module's file name (looked for in ../lib); `build_path`: where the build wrote
  /// it; `what`: how an error names it. IoError listing each place tried when none loads.
  Module(const std::string& file, const std::string& build_path, const std::string& what);
  ~Module();
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;
  /// The exported symbol `name`, or nullptr.
  void* symbol(const char* name) const;

private:
  void* m_handle = nullptr;
};

} // namespace vtb
