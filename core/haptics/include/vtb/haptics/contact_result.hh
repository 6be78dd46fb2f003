#pragma once
/// \file
/// What a proxy (god-object) contact reports each servo cycle, in 2D and in 3D alike.

#include <Eigen/Core>

#include <array>

namespace vtb {

template <int dim> struct ContactResult {
  bool touching = false;
  Eigen::Matrix<double, dim, 1> proxy = Eigen::Matrix<double, dim, 1>::Zero(); ///< the handle when not touching
  int facet = -1;                    ///< the touched boundary facet (edge in 2D, triangle in 3D)
  std::array<double, dim> weights{}; ///< barycentric weights of the proxy on the facet's nodes (sum 1)
};

} // namespace vtb
