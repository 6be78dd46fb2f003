#pragma once
/// \file
/// The gmsh API behind a module of its own (vtb_gmsh_backend.so), loaded on demand: libgmsh
/// and the OpenCASCADE and FLTK libraries it brings add about 40 MB to a process's resident
/// memory the moment they load (docs/meshes.md), so only the mesh reader's child process and a
/// mesh write load them; a run that meshes with CGAL never does. The module exports these
/// three functions by name (extern "C"); no exception crosses the boundary.

#include "vtb/meshes/mesh.hh"

#include <string>

namespace vtb::gmsh_backend {

/// Reads the file `src` with gmsh: *out = "M" + the serialized mesh, or "E" + the error.
using ReadFn = void(const char* src, std::string* out);
/// Writes `mesh` as .msh 4.1 to `path` (which must end in .msh); *error = "" or the error.
template <int dim> using WriteFn = void(const Mesh<dim>* mesh, const char* path, std::string* error);

inline constexpr const char* kRead = "vtb_gmsh_read";
template <int dim> inline constexpr const char* kWrite = dim == 2 ? "vtb_gmsh_write2" : "vtb_gmsh_write3";

} // namespace vtb::gmsh_backend
