#pragma once
/// \file
/// A tool tip of finite size: the facets of the deformed surface under a flat disc (3D) or a
/// flat segment (2D) of radius r centred at the proxy, and the weights by which the coupling's
/// force spreads over their nodes.
///
/// The tip presses as a pad of uniform pressure over the disc of radius r about the proxy,
/// measured across the touched facet's normal n: each node's weight is the integral of that
/// pressure against its hat function over the facets under the tip (connected to the touched
/// one, facing the same way: n_f . n > 0), by kSplit^2 samples per facet at its rest area,
/// scaled to sum 1. Its force converges with the mesh, where a point load (one facet's
/// barycentric weights) has a singular continuum answer. The tip's face is normal to the
/// god-object's direction (handle to its closest surface point, outward), and the proxy sits
/// at the footprint's weighted mean position along it: the point whose motion the force does
/// work on, so k w w^T is the coupling's exact stiffness (coupling_set.hh).
///
/// Where the tip is narrower than the facet it touches (r below its mean edge) the mesh cannot
/// resolve the pad: the weights spread the force over nodes farther apart than the tip is wide,
/// and the mesh answers as the continuum would to that wider load, stiffer than to the tip
/// (a disc's compliance goes as 1/r). The footprint says so (`resolved`) and carries the
/// compliance the mesh misses, in series with the coupling: the half-space's, between the
/// tip's radius r and the radius a_w of a uniform load with the weights' second moment (3D:
/// a_w^2 = 2 sum w_i rho_i^2, rho_i across n from their centre; 2D: a_w^2 = 3 sum w_i rho_i^2):
///   3D  C = 16 (1 - nu^2) / (3 pi^2 E) (1/r - 1/a_w)   (mean displacement under a uniform disc)
///   2D  C = 2 ln(a_w / r) / (pi E t)                    (plane stress, a strip on a half-plane)
/// and 0 where a_w <= r (a resolved tip). docs/haptics.md measures what it buys.
/// Allocation-free after construction.

#include "vtb/haptics/contact_result.hh"
#include "vtb/springs/spring_kernels.hh"

#include <vector>

namespace vtb {

template <int dim> class TipFootprint {
public:
  static constexpr int kMaxFacets = 512; ///< facets examined per query at most
  static constexpr int kSplit = 6;       ///< a facet's samples: kSplit per edge (kSplit^2 per triangle)

  /// `facets`: the boundary facets, outward oriented (kept by reference); `rest`: the rest
  /// positions; `radius`: the tip's radius (m), 0 for a point proxy; the body's Young's
  /// modulus (Pa), Poisson's ratio and (2D) thickness (m), for the compliance the mesh misses.
  TipFootprint(const std::vector<std::array<int, dim>>& facets, const Nodal<dim>& rest, double radius,
               double young_modulus = 0, double poisson_ratio = 0, double thickness = 1);

  double radius() const { return m_radius; }
  /// The surface's mean rest edge length (what a tip must exceed to be resolved).
  double mean_edge() const { return m_mean_edge; }

  /// Fills c.footprint and c.normal for a touching contact (c.facet, c.proxy on it, c.weights)
  /// of the handle at `handle`, the nodes at x, and moves c.proxy to the footprint's weighted
  /// mean along the normal.
  void place(ContactResult<dim>& c, const Vec<dim>& handle, const Nodal<dim>& x);

private:
  Vec<dim> normal(int f, const Nodal<dim>& x) const;
  Vec<dim> centroid(int f, const Nodal<dim>& x) const;
  void add(Footprint& fp, int node, double w) const;
  /// Adds facet f's share of the tip's pressure to fp; returns its samples under the tip.
  int press(int f, const Vec<dim>& centre, const Vec<dim>& n, const Nodal<dim>& x, Footprint& fp) const;

  const std::vector<std::array<int, dim>>& m_facets;
  Nodal<dim> m_rest; ///< the rest positions: the tip's patch is taken on the rest surface
  double m_radius;
  double m_soft = 0; ///< 3D: 16 (1 - nu^2) / (3 pi^2 E); 2D: 2 / (pi E t); 0: no correction
  double m_mean_edge = 0;
  std::vector<double> m_share;         ///< per facet: its rest area (length) / dim
  std::vector<int> m_ring_ptr, m_ring; ///< per facet: the facets sharing a node with it (CSR)
  std::vector<long> m_seen;            ///< per facet: the query that last queued it
  std::vector<int> m_queue;            ///< kMaxFacets
  long m_query = 0;
};

} // namespace vtb
