#pragma once
/// \file
/// Element quality: angles of triangles, dihedral angles and radius-edge ratios of tetrahedra.

#include "vtb/meshes/mesh.hh"

namespace vtb {

struct MeshQuality {
  double min_angle = 0, max_angle = 0; ///< degrees: triangle angles (2D) or dihedral angles (3D)
  double max_radius_edge = 0;          ///< circumradius / shortest edge (1/sqrt(3) = equilateral triangle)
  int inverted = 0;                    ///< cells with negative measure
  int degenerate = 0;                  ///< cells with measure below 1e-12 x (longest edge)^dim
};

template <int dim> MeshQuality mesh_quality(const Mesh<dim>& mesh);

} // namespace vtb
