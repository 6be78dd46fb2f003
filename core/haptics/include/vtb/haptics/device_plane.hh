#pragma once
/// \file
/// Where a planar (2-DOF) device acts in the body's space: world = origin + axes * device. In
/// 2D the plane is the body's own; in 3D the scene's [haptics.plane] places it (shared by
/// `vtb haptics` and the viewer's device mode).

#include "vtb/meshes/mesh.hh"
#include "vtb/problem/scene.hh"

#include <Eigen/Core>

namespace vtb {

template <int dim> struct DevicePlane {
  Eigen::Matrix<double, dim, 1> origin = Eigen::Matrix<double, dim, 1>::Zero();
  Eigen::Matrix<double, dim, 2> axes = Eigen::Matrix<double, dim, 2>::Identity();

  /// A device point in the body's space, and a body point taken to the device's plane.
  Eigen::Matrix<double, dim, 1> to_world(const Eigen::Vector2d& p) const { return origin + axes * p; }
  Eigen::Vector2d to_device(const Eigen::Matrix<double, dim, 1>& x) const { return axes.transpose() * (x - origin); }
};

/// The scene's plane: 2D, the identity (a [haptics.plane] is bad input); 3D, [haptics.plane],
/// else the x-y plane through the first waypoint given as a 3D point, else through the middle
/// of the body in z. A scene without [haptics] gets that default too.
template <int dim> DevicePlane<dim> device_plane(const Scene& scene, const Mesh<dim>& mesh);

} // namespace vtb
