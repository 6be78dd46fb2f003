#pragma once
/// \file
/// Structured generators: rectangles of triangles and boxes of tetrahedra.

#include "vtb/meshes/mesh.hh"

namespace vtb {

/// Rectangle [0, size.x] x [0, size.y] split into divisions.x x divisions.y squares, each
/// cut into two triangles with the diagonal mirrored in every other row and column (the
/// "union jack" pattern) so that the spring lattice has no directional bias.
/// Groups: left (x = 0), right (x = size.x), bottom (y = 0), top (y = size.y).
Mesh2 generate_rectangle(const Eigen::Vector2d& size, const Eigen::Vector2i& divisions);

/// Box [0, size] split into divisions cubes, each cut into six tetrahedra (Kuhn) mirrored
/// in every other layer along each axis; conforming, with alternating face diagonals.
/// Groups: left/right (x), bottom/top (y), front/back (z).
Mesh3 generate_box(const Eigen::Vector3d& size, const Eigen::Vector3i& divisions);

} // namespace vtb
