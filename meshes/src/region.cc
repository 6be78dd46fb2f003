#include "vtb/meshes/region.hh"

#include <sstream>

#include "vtb/base/input_error.hh"

#include <algorithm>
#include <limits>

namespace vtb {

template <int dim> std::vector<int> nodes_in_box(const Mesh<dim>& mesh, const Box<dim>& box) {
  const double grow = 1e-9 * bounding_diagonal(mesh);
  const auto lo = (box.min.array() - grow).matrix().eval();
  const auto hi = (box.max.array() + grow).matrix().eval();
  std::vector<int> out;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto p = mesh.points.col(i);
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) out.push_back(i);
  }
  return out;
}

template <int dim> int nearest_node(const Mesh<dim>& mesh, const Eigen::Matrix<double, dim, 1>& p) {
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const double d = (mesh.points.col(i) - p).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

std::optional<AxisFace> axis_face_of(const std::string& name, int dim) {
  if (name.size() != 5 || name[1] != '_' || (name.compare(2, 3, "min") != 0 && name.compare(2, 3, "max") != 0))
    return std::nullopt;
  const int axis = name[0] - 'x';
  if (axis < 0 || axis >= dim) return std::nullopt;
  return AxisFace{axis, name.compare(2, 3, "max") == 0};
}

template <int dim>
Selection<dim> select_axis_face(const Mesh<dim>& mesh, const AxisFace& face, const std::string& what) {
  const auto row = mesh.points.row(face.axis);
  const double plane = face.max_side ? row.maxCoeff() : row.minCoeff();
  // The generators place a face's nodes on the plane exactly; a mesh file's round trip keeps
  // them within its printed digits, far inside 1e-9 of the body's diagonal.
  const double tol = 1e-9 * bounding_diagonal(mesh);
  const auto on = [&](int v) { return std::abs(mesh.points(face.axis, v) - plane) <= tol; };
  Selection<dim> s;
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (on(i)) s.nodes.push_back(i);
  for (const auto& f : boundary_facets(mesh))
    if (std::all_of(f.begin(), f.end(), on)) s.facets.push_back(f);
  if (s.facets.empty()) {
    const std::string name = std::string(1, static_cast<char>('x' + face.axis)) + (face.max_side ? "_max" : "_min");
    std::ostringstream os;
    os << what << ": group \"" << name << "\": mesh " << mesh.source << " has no flat face at its "
       << (face.max_side ? "largest " : "smallest ") << static_cast<char>('x' + face.axis) << " (" << plane
       << " m), only " << s.nodes.size() << " node(s) there; name a group of the mesh or a box";
    throw InputError(os.str());
  }
  return s;
}

template <int dim> Selection<dim> select(const Mesh<dim>& mesh, const RegionSpec<dim>& spec, const std::string& what) {
  Selection<dim> s;
  if (spec.box) {
    s.nodes = nodes_in_box(mesh, *spec.box);
    std::vector<char> inside(static_cast<std::size_t>(mesh.num_nodes()), 0);
    for (int i : s.nodes) inside[static_cast<std::size_t>(i)] = 1;
    for (const auto& f : boundary_facets(mesh))
      if (std::all_of(f.begin(), f.end(), [&](int v) { return inside[static_cast<std::size_t>(v)] != 0; }))
        s.facets.push_back(f);
  } else if (!spec.group.empty()) {
    const auto it = mesh.groups.find(spec.group);
    if (it != mesh.groups.end()) {
      s.nodes = it->second.nodes;
      s.facets = it->second.facets;
    } else if (const auto face = axis_face_of(spec.group, dim)) {
      s = select_axis_face(mesh, *face, what);
    } else {
      std::string known;
      for (const auto& [name, g] : mesh.groups) known += (known.empty() ? "" : ", ") + name;
      throw InputError(what + ": group \"" + spec.group + "\" is not in mesh " + mesh.source +
                       " (groups: " + (known.empty() ? "none" : known) + "; and the faces by axis, " +
                       (dim == 3 ? "x_min, x_max, y_min, y_max, z_min, z_max" : "x_min, x_max, y_min, y_max") + ")");
    }
  } else if (spec.point) {
    s.nodes = {nearest_node(mesh, *spec.point)};
  } else if (spec.disc) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& f : boundary_facets(mesh)) {
      Eigen::Matrix<double, dim, 1> c = Eigen::Matrix<double, dim, 1>::Zero();
      for (int v : f) c += mesh.points.col(v) / dim;
      const double d = (c - spec.disc->center).norm();
      nearest = std::min(nearest, d);
      if (d <= spec.disc->radius) {
        s.facets.push_back(f);
        s.nodes.insert(s.nodes.end(), f.begin(), f.end());
      }
    }
    if (s.facets.empty()) {
      std::ostringstream os;
      os << what << ": disc of radius " << spec.disc->radius << " m holds no boundary facet centre of mesh "
         << mesh.source << " (the nearest is " << nearest << " m from the centre); enlarge the radius";
      throw InputError(os.str());
    }
    std::sort(s.nodes.begin(), s.nodes.end());
    s.nodes.erase(std::unique(s.nodes.begin(), s.nodes.end()), s.nodes.end());
  }
  return s;
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template std::vector<int> nodes_in_box<D>(const Mesh<D>&, const Box<D>&);                                            \
  template int nearest_node<D>(const Mesh<D>&, const Eigen::Matrix<double, D, 1>&);                                    \
  template Selection<D> select<D>(const Mesh<D>&, const RegionSpec<D>&, const std::string&);                           \
  template Selection<D> select_axis_face<D>(const Mesh<D>&, const AxisFace&, const std::string&);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

} // namespace vtb
