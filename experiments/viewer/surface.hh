#pragma once
/// \file
/// What the viewer draws of a mesh: the triangles (a 2D mesh's cells, or a tet mesh's
/// boundary faces, outward), the cell each belongs to (for its strain colour, from
/// core's cell_max_principal_strain), the outline edges, and the boundary nodes a pull may grab.

#include "vtb/meshes/mesh.hh"
#include "vtb/springs/spring_kernels.hh"

#include <array>
#include <vector>

namespace vtb::viewer {

template <int dim> struct Surface {
  std::vector<std::array<int, 3>> tris;  ///< node indices, counter-clockwise seen from outside
  std::vector<int> owner;                ///< the cell of each triangle
  std::vector<std::array<int, 2>> edges; ///< mesh edges drawn as lines (2D: all; 3D: of the boundary)
  std::vector<int> boundary_nodes;       ///< sorted, unique
};

template <int dim> Surface<dim> make_surface(const Mesh<dim>& mesh);

/// Among `candidates`, the node nearest to p (positions X + u); -1 if there is none.
template <int dim>
int nearest_of(const std::vector<int>& candidates, const Mesh<dim>& mesh, const Nodal<dim>& u, const Vec<dim>& p);

} // namespace vtb::viewer
