#pragma once
/// \file
/// VTK XML unstructured grids (.vtu) for ParaView: the mesh, optionally with a displacement.

#include "vtb/meshes/mesh.hh"

#include <filesystem>

namespace vtb {

/// Writes `mesh` (and, if non-empty, a per-node `displacement` with dim rows) as ASCII .vtu.
template <int dim>
void write_vtu(const Mesh<dim>& mesh, const std::filesystem::path& file,
               const Eigen::Matrix<double, dim, Eigen::Dynamic>& displacement = {});

} // namespace vtb
