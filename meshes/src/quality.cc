#include "vtb/meshes/quality.hh"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace vtb {

template <int dim> MeshQuality mesh_quality(const Mesh<dim>& mesh) {
  MeshQuality q;
  q.min_angle = 180;
  constexpr double deg = 180.0 / std::numbers::pi;
  for (const auto& c : mesh.cells) {
    double lmin = 1e300, lmax = 0;
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b) {
        const double l = (mesh.points.col(c[a]) - mesh.points.col(c[b])).norm();
        lmin = std::min(lmin, l);
        lmax = std::max(lmax, l);
      }
    const double vol = signed_measure(mesh, c);
    if (vol < 0) ++q.inverted;
    if (std::abs(vol) <= 1e-12 * std::pow(lmax, dim)) {
      ++q.degenerate;
      continue;
    }
    if constexpr (dim == 2) {
      for (int a = 0; a < 3; ++a) {
        const Eigen::Vector2d u = mesh.points.col(c[(a + 1) % 3]) - mesh.points.col(c[a]);
        const Eigen::Vector2d v = mesh.points.col(c[(a + 2) % 3]) - mesh.points.col(c[a]);
        const double ang = std::acos(std::clamp(u.dot(v) / (u.norm() * v.norm()), -1.0, 1.0)) * deg;
        q.min_angle = std::min(q.min_angle, ang);
        q.max_angle = std::max(q.max_angle, ang);
      }
      // R = abc / (4 A).
      const double a = (mesh.points.col(c[1]) - mesh.points.col(c[0])).norm();
      const double b = (mesh.points.col(c[2]) - mesh.points.col(c[1])).norm();
      const double e = (mesh.points.col(c[0]) - mesh.points.col(c[2])).norm();
      q.max_radius_edge = std::max(q.max_radius_edge, a * b * e / (4 * std::abs(vol)) / lmin);
    } else {
      // Dihedral angle at edge (a, b) between the faces (a, b, c) and (a, b, d).
      static constexpr int pairs[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                          {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
      for (const auto& p : pairs) {
        const Eigen::Vector3d a = mesh.points.col(c[p[0]]), b = mesh.points.col(c[p[1]]);
        const Eigen::Vector3d e = (b - a).normalized();
        Eigen::Vector3d u = mesh.points.col(c[p[2]]) - a, v = mesh.points.col(c[p[3]]) - a;
        u -= u.dot(e) * e;
        v -= v.dot(e) * e;
        const double ang = std::acos(std::clamp(u.dot(v) / (u.norm() * v.norm()), -1.0, 1.0)) * deg;
        q.min_angle = std::min(q.min_angle, ang);
        q.max_angle = std::max(q.max_angle, ang);
      }
      // Circumradius from the circumcentre solve.
      Eigen::Matrix3d A;
      Eigen::Vector3d rhs;
      const Eigen::Vector3d p0 = mesh.points.col(c[0]);
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d d = mesh.points.col(c[k + 1]) - p0;
        A.row(k) = 2 * d.transpose();
        rhs[k] = d.squaredNorm();
      }
      const double R = A.partialPivLu().solve(rhs).norm();
      q.max_radius_edge = std::max(q.max_radius_edge, R / lmin);
    }
  }
  return q;
}

template MeshQuality mesh_quality<2>(const Mesh<2>&);
template MeshQuality mesh_quality<3>(const Mesh<3>&);

} // namespace vtb
