#pragma once
/// \file
/// Gmsh .msh files through the gmsh API (versions 2.2 and 4.x).

#include "vtb/meshes/mesh.hh"

#include <filesystem>

namespace vtb {

/// Reads triangles (2D) or tetrahedra (3D) and the physical groups of a .msh file.
/// Physical groups of dimension dim-1 become boundary groups with facets; groups of other
/// dimensions become node groups. Throws InputError naming the file on any problem.
AnyMesh read_msh(const std::filesystem::path& file);

/// Writes a mesh and its facet groups as .msh 4.1. Refuses to overwrite nothing half-written:
/// the file is written to a temporary name and renamed.
template <int dim> void write_msh(const Mesh<dim>& mesh, const std::filesystem::path& file);

} // namespace vtb
