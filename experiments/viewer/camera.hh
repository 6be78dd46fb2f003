#pragma once
/// \file
/// The viewer's camera: orthographic over a plate (pan and zoom), or an orbit camera around
/// a solid (yaw, pitch, distance). Maps scene points to the window and the cursor back.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vtb::viewer {

struct Camera {
  bool perspective = false;
  Eigen::Vector3d center = Eigen::Vector3d::Zero(); ///< what the view is centred on
  double extent = 1.0;                              ///< half the visible height (2D), scene radius (3D)
  double zoom = 1.0;
  double yaw = 0.6, pitch = 0.45; ///< 3D orbit angles, rad
  int width = 1, height = 1;      ///< framebuffer pixels of the drawing area
  int left = 0;                   ///< the drawing area's left edge (the panel is left of it)

  Eigen::Matrix4d view() const {
    if (!perspective) {
      Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
      v.block<3, 1>(0, 3) = -center;
      return v;
    }
    const Eigen::Vector3d eye = center + distance() * direction();
    const Eigen::Vector3d f = (center - eye).normalized();
    const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
    const Eigen::Vector3d s = f.cross(up).normalized(), u = s.cross(f);
    Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
    v.block<1, 3>(0, 0) = s.transpose();
    v.block<1, 3>(1, 0) = u.transpose();
    v.block<1, 3>(2, 0) = -f.transpose();
    v(0, 3) = -s.dot(eye);
    v(1, 3) = -u.dot(eye);
    v(2, 3) = f.dot(eye);
    return v;
  }
  Eigen::Matrix4d projection() const {
    const double aspect = static_cast<double>(width) / std::max(1, height);
    Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
    if (!perspective) {
      const double h = extent / zoom, w = h * aspect;
      p(0, 0) = 1 / w;
      p(1, 1) = 1 / h;
      p(2, 2) = -1e-3;
      p(3, 3) = 1;
      return p;
    }
    const double fov = 0.7, n = 0.01 * distance(), fa = 100 * distance();
    const double t = 1 / std::tan(fov / 2);
    p(0, 0) = t / aspect;
    p(1, 1) = t;
    p(2, 2) = (fa + n) / (n - fa);
    p(2, 3) = 2 * fa * n / (n - fa);
    p(3, 2) = -1;
    return p;
  }
  Eigen::Matrix4d mvp() const { return projection() * view(); }
  double distance() const { return 2.6 * extent / zoom; }
  Eigen::Vector3d direction() const {
    return {std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw)};
  }

  /// Window pixel (x right, y down, relative to the whole window) of a scene point.
  Eigen::Vector2d to_window(const Eigen::Vector3d& p) const {
    const Eigen::Vector4d c = mvp() * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    const double x = c.x() / c.w(), y = c.y() / c.w();
    return {left + (x + 1) / 2 * width, (1 - y) / 2 * height};
  }
  /// The scene point under a window pixel on the plane through `on` facing the camera
  /// (z = 0 in 2D).
  Eigen::Vector3d from_window(const Eigen::Vector2d& px, const Eigen::Vector3d& on) const {
    return on_plane(px, on, perspective ? direction() : Eigen::Vector3d::UnitZ());
  }
  /// The scene point under a window pixel on the plane through `on` with normal n (the cursor's
  /// ray meets it; the near point when the ray runs along it).
  Eigen::Vector3d on_plane(const Eigen::Vector2d& px, const Eigen::Vector3d& on, const Eigen::Vector3d& n) const {
    const double x = 2 * (px.x() - left) / width - 1, y = 1 - 2 * px.y() / height;
    const Eigen::Matrix4d inv = mvp().inverse();
    auto unproject = [&](double z) {
      const Eigen::Vector4d h = inv * Eigen::Vector4d(x, y, z, 1.0);
      return Eigen::Vector3d(h.head<3>() / h.w());
    };
    const Eigen::Vector3d a = unproject(-1), b = unproject(1);
    const double denom = n.dot(b - a);
    if (std::abs(denom) < 1e-300) return a;
    return a + (n.dot(on - a) / denom) * (b - a);
  }
};

} // namespace vtb::viewer
