#include "vtb/haptics/device_plane.hh"

#include "vtb/base/input_error.hh"

namespace vtb {

template <int dim> DevicePlane<dim> device_plane(const Scene& scene, const Mesh<dim>& mesh) {
  DevicePlane<dim> plane;
  const bool has_plane = scene.haptics && scene.haptics->plane;
  if constexpr (dim == 2) {
    if (has_plane)
      throw InputError(scene.file.string() + ": [haptics.plane] places the device in a 3D body; this mesh is 2D");
  } else {
    if (has_plane) {
      plane.origin = scene.haptics->plane->origin;
      plane.axes << scene.haptics->plane->x_axis, scene.haptics->plane->y_axis;
    } else {
      // The device's x-y plane through the first waypoint given as a 3D point, else through
      // the middle of the body in z.
      plane.origin.z() = 0.5 * (mesh.points.row(2).minCoeff() + mesh.points.row(2).maxCoeff());
      const HandDesc* hand = scene.haptics && scene.haptics->hand ? &*scene.haptics->hand : nullptr;
      if (hand && !hand->waypoints.empty() && hand->waypoints.front().size() == 3)
        plane.origin.z() = hand->waypoints.front()[2];
    }
  }
  return plane;
}

template DevicePlane<2> device_plane<2>(const Scene&, const Mesh<2>&);
template DevicePlane<3> device_plane<3>(const Scene&, const Mesh<3>&);

} // namespace vtb
