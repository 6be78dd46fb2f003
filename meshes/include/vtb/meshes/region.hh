#pragma once
/// \file
/// Selecting nodes and boundary facets by box, group or point.

#include "vtb/meshes/mesh.hh"

#include <optional>

namespace vtb {

/// Axis-aligned closed box, grown by 1e-9 x the mesh diagonal when selecting.
template <int dim> struct Box {
  Eigen::Matrix<double, dim, 1> min;
  Eigen::Matrix<double, dim, 1> max;
};

/// A patch of the boundary: the boundary facets whose centroid lies within `radius` of
/// `center` (a tool tip pressing on the surface).
template <int dim> struct Disc {
  Eigen::Matrix<double, dim, 1> center;
  double radius = 0;
};

/// What a region of a scene names: a box, a mesh group, a point (its nearest node) or a disc
/// (a patch of boundary facets).
template <int dim> struct RegionSpec {
  std::optional<Box<dim>> box;
  std::string group;
  std::optional<Eigen::Matrix<double, dim, 1>> point;
  std::optional<Disc<dim>> disc;
};

/// A selection: its nodes (sorted), and the boundary facets it covers (for tractions).
template <int dim> struct Selection {
  std::vector<int> nodes;
  std::vector<std::array<int, dim>> facets;
};

/// Nodes inside the (grown) box, sorted.
template <int dim> std::vector<int> nodes_in_box(const Mesh<dim>& mesh, const Box<dim>& box);

/// The node nearest to p (lowest index on ties).
template <int dim> int nearest_node(const Mesh<dim>& mesh, const Eigen::Matrix<double, dim, 1>& p);

/// A face of the body named by its axis: `x_min`, `x_max`, `y_min`, ... (`z_min` is the face at
/// the smallest z, the base of a body whose up is z).
struct AxisFace {
  int axis = 0;
  bool max_side = false;
};

/// The face `name` names ("x_min" ... "z_max", the axis below `dim`), or nothing.
std::optional<AxisFace> axis_face_of(const std::string& name, int dim);

/// The nodes at the body's smallest (largest) coordinate on the face's axis, within 1e-9 of the
/// body's diagonal, and the boundary facets all of whose vertices lie there. On a generated box,
/// slab or rectangle it is the named face (`z_min` = `front`, `y_min` = `bottom`, ...). Throws
/// InputError (naming `what`) where no boundary facet lies there (a curved body's extreme).
template <int dim>
Selection<dim> select_axis_face(const Mesh<dim>& mesh, const AxisFace& face, const std::string& what);

/// Resolves a region against a mesh. A box selects nodes inside it and the boundary facets
/// whose vertices all lie inside it; a group selects its nodes and facets; a point selects
/// its nearest node and no facet. A group the mesh does not hold that names a face by axis
/// (`z_min`, ...) selects that face (select_axis_face). Throws InputError (naming `what`) if the
/// group is unknown.
template <int dim> Selection<dim> select(const Mesh<dim>& mesh, const RegionSpec<dim>& spec, const std::string& what);

} // namespace vtb
