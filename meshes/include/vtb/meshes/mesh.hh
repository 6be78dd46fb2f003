#pragma once
/// \file
/// Simplex meshes in 2D (triangles) and 3D (tetrahedra) with named groups.
/// The mesh knows nothing of springs or finite elements: it is points, cells and groups.

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace vtb {

/// A named set of nodes; boundary groups also carry their facets (edges in 2D,
/// triangles in 3D) so that a traction can be integrated over them.
template <int dim> struct MeshGroup {
  std::vector<int> nodes;                   ///< sorted, unique
  std::vector<std::array<int, dim>> facets; ///< empty for node-only groups
};

/// Triangle (dim = 2) or tetrahedron (dim = 3) mesh. Cells are positively oriented
/// (counter-clockwise triangles, right-handed tetrahedra) once `check_and_orient` ran.
template <int dim> struct Mesh {
  static_assert(dim == 2 || dim == 3, "vtb meshes are 2D or 3D");
  static constexpr int cell_vertices = dim + 1;
  static constexpr int points_dim = dim;
  using Point = Eigen::Matrix<double, dim, 1>;
  using Cell = std::array<int, dim + 1>;
  using Facet = std::array<int, dim>;

  Eigen::Matrix<double, dim, Eigen::Dynamic> points; ///< one column per node
  std::vector<Cell> cells;
  std::map<std::string, MeshGroup<dim>> groups;
  std::string source = "mesh"; ///< file name or generator, for error messages

  int num_nodes() const { return static_cast<int>(points.cols()); }
  int num_cells() const { return static_cast<int>(cells.size()); }
};

using Mesh2 = Mesh<2>;
using Mesh3 = Mesh<3>;
/// A mesh whose dimension is known only at run time (read from a file, chosen by a scene).
using AnyMesh = std::variant<Mesh2, Mesh3>;

inline int dimension(const AnyMesh& m) {
  return m.index() == 0 ? 2 : 3;
}

/// Signed measure of a cell: area (2D) or volume (3D); positive when well oriented.
template <int dim> double signed_measure(const Mesh<dim>& mesh, const typename Mesh<dim>::Cell& cell);

/// Measure of a facet: length (2D) or area (3D).
template <int dim> double facet_measure(const Mesh<dim>& mesh, const typename Mesh<dim>::Facet& facet);

/// Unique undirected edges (i < j), sorted lexicographically.
template <int dim> std::vector<std::array<int, 2>> unique_edges(const Mesh<dim>& mesh);

/// Facets that belong to exactly one cell (the boundary), oriented as in their cell.
template <int dim> std::vector<typename Mesh<dim>::Facet> boundary_facets(const Mesh<dim>& mesh);

/// Length of the bounding-box diagonal.
template <int dim> double bounding_diagonal(const Mesh<dim>& mesh);

/// Validates an untrusted mesh and orients its cells in place. Throws vtb::InputError
/// naming `mesh.source`, the cell or node and the problem for: an index out of range, a
/// non-finite coordinate, a repeated vertex, a zero-measure cell, a duplicate cell, a node
/// used by no cell. Inverted cells are re-oriented; the count is returned.
template <int dim> int check_and_orient(Mesh<dim>& mesh);

} // namespace vtb
