#pragma once
/// \file
/// What a proxy (god-object) contact reports each servo cycle, in 2D and in 3D alike.

#include <Eigen/Core>

#include <array>

namespace vtb {

/// The nodes a contact's force acts on, with their weights (sum 1): the touched facet's by the
/// proxy's barycentric weights (a point proxy), or a tool tip's footprint (footprint.hh).
struct Footprint {
  static constexpr int kMaxNodes = 64; ///< a footprint's nodes at most (the couplings' per unit)
  int count = 0;
  std::array<int, kMaxNodes> node{};
  std::array<double, kMaxNodes> weight{};
  int facets = 0;         ///< facets under the tip (1: a point proxy)
  bool resolved = true;   ///< false: the tip is smaller than the facet it touches
  bool truncated = false; ///< the tip covered more than kMaxNodes nodes; the rest took no share
  /// m/N: the tip's local compliance the mesh misses where the footprint's weights spread wider
  /// than the tip (footprint.hh), in series with the coupling (tip_stiffness); 0 if none.
  double compliance = 0;
};

/// The coupling's stiffness k in series with the footprint's missing local compliance.
inline double tip_stiffness(double k, const Footprint& fp) {
  return k / (1.0 + k * fp.compliance);
}

template <int dim> struct ContactResult {
  bool touching = false;
  Eigen::Matrix<double, dim, 1> proxy = Eigen::Matrix<double, dim, 1>::Zero(); ///< the handle when not touching
  int facet = -1;                    ///< the touched boundary facet (edge in 2D, triangle in 3D)
  std::array<double, dim> weights{}; ///< barycentric weights of the proxy on the facet's nodes (sum 1)
  Footprint footprint;               ///< where the force acts (filled by TipFootprint::place)
  Eigen::Matrix<double, dim, 1> normal = Eigen::Matrix<double, dim, 1>::Zero(); ///< the tip's face's outward normal
};

} // namespace vtb
