// The nominal pressure under a scene's loads (load_pressure.hh).
#include "vtb/springs/load_pressure.hh"

#include <Eigen/Geometry>

#include <algorithm>

namespace vtb {

template <int dim>
double deepest_load_pressure(const Mesh<dim>& mesh, const Eigen::MatrixXd& nodal_loads, double young_modulus,
                             double thickness) {
  if (nodal_loads.size() == 0 || !(young_modulus > 0)) return 0.0;
  const int n = mesh.num_nodes();
  Eigen::VectorXd share = Eigen::VectorXd::Zero(n);
  Eigen::Matrix<double, dim, Eigen::Dynamic> normal = Eigen::Matrix<double, dim, Eigen::Dynamic>::Zero(dim, n);
  const double depth = dim == 2 ? thickness : 1.0;
  for (const auto& facet : boundary_facets(mesh)) { // outward for the positively oriented cells
    Eigen::Matrix<double, dim, 1> area;             // the facet's outward normal times its measure
    if constexpr (dim == 2) {
      const Eigen::Vector2d d = mesh.points.col(facet[1]) - mesh.points.col(facet[0]);
      area = Eigen::Vector2d(d.y(), -d.x());
    } else {
      const Eigen::Vector3d a = mesh.points.col(facet[0]);
      const Eigen::Vector3d b = Eigen::Vector3d(mesh.points.col(facet[1])) - a,
                            c = Eigen::Vector3d(mesh.points.col(facet[2])) - a;
      area = 0.5 * b.cross(c);
    }
    area *= depth / dim;
    for (const int v : facet) {
      share[v] += area.norm();
      normal.col(v) += area;
    }
  }
  double deepest = 0;
  for (int v = 0; v < n && v < nodal_loads.rows() / dim; ++v) {
    if (!(share[v] > 0) || normal.col(v).squaredNorm() == 0) continue; // an inner node: no press
    const Eigen::Matrix<double, dim, 1> f = nodal_loads.col(0).segment<dim>(static_cast<Eigen::Index>(dim) * v);
    deepest = std::max(deepest, -f.dot(normal.col(v).normalized()) / share[v]); // inward: a press
  }
  return deepest / young_modulus;
}

template double deepest_load_pressure<2>(const Mesh<2>&, const Eigen::MatrixXd&, double, double);
template double deepest_load_pressure<3>(const Mesh<3>&, const Eigen::MatrixXd&, double, double);

} // namespace vtb
