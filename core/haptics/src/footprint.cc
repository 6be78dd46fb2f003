#include "vtb/haptics/footprint.hh"
#include "vtb/haptics/facet_rings.hh"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vtb {

template <int dim>
TipFootprint<dim>::TipFootprint(const std::vector<std::array<int, dim>>& facets, const Nodal<dim>& rest, double radius,
                                double young_modulus, double poisson_ratio, double thickness)
    : m_facets(facets), m_radius(radius), m_seen(facets.size(), -1), m_queue(kMaxFacets) {
  if (young_modulus > 0)
    m_soft = dim == 3 ? 16.0 * (1.0 - poisson_ratio * poisson_ratio) / (3.0 * M_PI * M_PI * young_modulus)
                      : 2.0 / (M_PI * young_modulus * thickness);
  double edges = 0;
  for (std::size_t f = 0; f < facets.size(); ++f) {
    const auto& e = facets[f];
    double size = 0;
    if constexpr (dim == 2) {
      size = (rest.col(e[1]) - rest.col(e[0])).norm();
      edges += size;
    } else {
      const Eigen::Vector3d a = rest.col(e[0]), b = rest.col(e[1]), c = rest.col(e[2]);
      size = 0.5 * (b - a).cross(c - a).norm();
      edges += (b - a).norm() + (c - b).norm() + (a - c).norm();
    }
    m_share.push_back(size / dim);
  }
  m_rest = rest;
  const double edge_count = static_cast<double>(facets.size()) * (dim == 2 ? 1.0 : 3.0);
  m_mean_edge = facets.empty() ? 0.0 : edges / edge_count;
  facet_rings(facets, static_cast<int>(rest.cols()), m_ring_ptr, m_ring);
}

template <int dim> Vec<dim> TipFootprint<dim>::normal(int f, const Nodal<dim>& x) const {
  const auto& e = m_facets[static_cast<std::size_t>(f)];
  if constexpr (dim == 2) {
    const Eigen::Vector2d d = x.col(e[1]) - x.col(e[0]); // counter-clockwise loops: the body on the left
    return Eigen::Vector2d(d.y(), -d.x()).normalized();
  } else {
    const Eigen::Vector3d a = x.col(e[0]);
    return (Eigen::Vector3d(x.col(e[1])) - a).cross(Eigen::Vector3d(x.col(e[2])) - a).normalized();
  }
}

template <int dim> Vec<dim> TipFootprint<dim>::centroid(int f, const Nodal<dim>& x) const {
  Vec<dim> g = Vec<dim>::Zero();
  for (int v : m_facets[static_cast<std::size_t>(f)]) g += x.col(v);
  return g / dim;
}

template <int dim> void TipFootprint<dim>::add(Footprint& fp, int node, double w) const {
  for (int k = 0; k < fp.count; ++k)
    if (fp.node[static_cast<std::size_t>(k)] == node) {
      fp.weight[static_cast<std::size_t>(k)] += w;
      return;
    }
  if (fp.count == Footprint::kMaxNodes) {
    fp.truncated = true;
    return;
  }
  fp.node[static_cast<std::size_t>(fp.count)] = node;
  fp.weight[static_cast<std::size_t>(fp.count++)] = w;
}

template <int dim>
int TipFootprint<dim>::press(int f, const Vec<dim>& centre, const Vec<dim>& n, const Nodal<dim>& x,
                             Footprint& fp) const {
  // The facet's samples: the centroids of kSplit^(dim-1) equal parts (of an edge in 2D, of the
  // triangle in 3D), each carrying its area (length) to the facet's nodes by its barycentric
  // weights where it lies within the radius across n. So each node gets the integral of the
  // tip's uniform pressure against its hat function, up to the samples' resolution.
  const auto& e = m_facets[static_cast<std::size_t>(f)];
  const double part = dim * m_share[static_cast<std::size_t>(f)] / (dim == 2 ? kSplit : kSplit * kSplit);
  std::array<double, dim> w{};
  int inside = 0;
  // The rim is soft over one sample's spacing (h / kSplit, h the facet's size), so a sample
  // crossing it moves the weights continuously: a hard rim made them jump as the surface moved
  // under a held tip, and the force with them (a 2D press rang at 20 %).
  const double size = dim == 2 ? dim * m_share[static_cast<std::size_t>(f)]
                               : std::sqrt(2.0 * dim * m_share[static_cast<std::size_t>(f)]);
  const double rim = size / kSplit;
  const auto sample = [&](const std::array<double, dim>& b) {
    Vec<dim> p = Vec<dim>::Zero();
    for (int k = 0; k < dim; ++k) p += b[static_cast<std::size_t>(k)] * x.col(e[static_cast<std::size_t>(k)]);
    const Vec<dim> d = p - centre;
    const double in = std::clamp((m_radius - (d - n * n.dot(d)).norm()) / rim + 0.5, 0.0, 1.0);
    if (!(in > 0)) return;
    ++inside;
    for (int k = 0; k < dim; ++k) w[static_cast<std::size_t>(k)] += in * part * b[static_cast<std::size_t>(k)];
  };
  if constexpr (dim == 2) {
    for (int i = 0; i < kSplit; ++i) {
      const double t = (i + 0.5) / kSplit;
      sample({1 - t, t});
    }
  } else { // the kSplit^2 sub-triangles' centroids: kSplit (kSplit + 1) / 2 upright, the rest inverted
    for (int i = 0; i < kSplit; ++i)
      for (int j = 0; i + j < kSplit; ++j) {
        sample({(i + 1.0 / 3) / kSplit, (j + 1.0 / 3) / kSplit, 1 - (i + j + 2.0 / 3) / kSplit});
        if (i + j + 1 < kSplit)
          sample({(i + 2.0 / 3) / kSplit, (j + 2.0 / 3) / kSplit, 1 - (i + j + 4.0 / 3) / kSplit});
      }
  }
  if (inside == 0) return 0;
  for (int k = 0; k < dim; ++k) add(fp, e[static_cast<std::size_t>(k)], w[static_cast<std::size_t>(k)]);
  return inside;
}

template <int dim> void TipFootprint<dim>::place(ContactResult<dim>& c, const Vec<dim>& handle, const Nodal<dim>& x) {
  Footprint& fp = c.footprint;
  fp = Footprint{};
  if (!c.touching || c.facet < 0) return;
  const int start = c.facet;
  const auto& touched = m_facets[static_cast<std::size_t>(start)];
  // The tip presses a patch of the body's material: the disc about the proxy's material point
  // on the rest surface. Measured on the deformed surface, the facets under it and their
  // weights followed the dent the tip itself made, and on a soft block the force flipped
  // between two levels (50 % apart) every few cycles as facets tilted in and out of the disc.
  const auto& rest = m_rest;
  Vec<dim> centre = Vec<dim>::Zero();
  for (int k = 0; k < dim; ++k)
    centre += c.weights[static_cast<std::size_t>(k)] * rest.col(touched[static_cast<std::size_t>(k)]);
  // The touched facet's mean edge: the tip resolves the surface where it is at least as wide.
  double edge = 0; // 2D: the edge's length; 3D: the triangle's mean edge
  for (int k = 0; k < dim; ++k)
    edge +=
        (rest.col(touched[static_cast<std::size_t>(k)]) - rest.col(touched[static_cast<std::size_t>((k + 1) % dim)]))
            .norm();
  edge /= dim;
  fp.resolved = m_radius >= edge;
  const Vec<dim> n = normal(start, rest);
  c.normal = normal(start, x);
  // The facets under the tip: from the touched one over facets sharing a node, each taken
  // while some of its samples lie under the tip and it faces the same way.
  ++m_query;
  std::size_t head = 0, size = 0;
  m_queue[size++] = start;
  m_seen[static_cast<std::size_t>(start)] = m_query;
  Vec<dim> face = Vec<dim>::Zero(); // the footprint's mean normal, by the facets' pressed samples
  while (m_radius > 0 && head < size) {
    const int f = m_queue[head++];
    if (f != start && !(normal(f, rest).dot(n) > 0)) continue;
    const int pressed = press(f, centre, n, rest, fp);
    if (pressed == 0) continue;
    face += pressed * m_share[static_cast<std::size_t>(f)] * normal(f, x);
    ++fp.facets;
    const auto b = static_cast<std::size_t>(m_ring_ptr[static_cast<std::size_t>(f)]);
    const auto e = static_cast<std::size_t>(m_ring_ptr[static_cast<std::size_t>(f) + 1]);
    for (std::size_t p = b; p < e && size < m_queue.size(); ++p) {
      const int g = m_ring[p];
      if (m_seen[static_cast<std::size_t>(g)] == m_query) continue;
      m_seen[static_cast<std::size_t>(g)] = m_query;
      m_queue[size++] = g;
    }
  }
  if (fp.count == 0) { // a point proxy, or a tip between the samples: the touched facet by barycentric weights
    for (int k = 0; k < dim; ++k) add(fp, touched[static_cast<std::size_t>(k)], c.weights[static_cast<std::size_t>(k)]);
    fp.facets = 1;
    return;
  }
  // The tip's face: normal to the god-object's direction d from the handle to its closest
  // surface point (outward) blended with the footprint's mean normal over the tip's size,
  // d + r n_mean. Deep in a press d leads and the tip centres itself as a point proxy does;
  // where the handle is within a fraction of r of the surface d's direction is noise and the
  // mean normal leads. Measured on the 2D press: the touched facet's normal alone jumps from
  // facet to facet (the force rang sideways at 0.1 N), the mean normal alone let the tip slide
  // off the soft plate, d alone flipped the force's direction every few cycles.
  const Vec<dim> to_surface = c.proxy - handle;
  const Vec<dim> mean_normal = face.squaredNorm() > 0 ? Vec<dim>(face.normalized()) : n;
  const Vec<dim> blend =
      (to_surface.dot(mean_normal) >= 0 ? to_surface : Vec<dim>(-to_surface)) + m_radius * mean_normal;
  c.normal = blend.normalized();
  double sum = 0;
  for (int k = 0; k < fp.count; ++k) sum += fp.weight[static_cast<std::size_t>(k)];
  Vec<dim> mean = Vec<dim>::Zero(), rest_mean = Vec<dim>::Zero();
  for (int k = 0; k < fp.count; ++k) {
    fp.weight[static_cast<std::size_t>(k)] /= sum;
    mean += fp.weight[static_cast<std::size_t>(k)] * x.col(fp.node[static_cast<std::size_t>(k)]);
    rest_mean += fp.weight[static_cast<std::size_t>(k)] * rest.col(fp.node[static_cast<std::size_t>(k)]);
  }
  // The radius of the uniform load with the weights' second moment across n (on the rest
  // surface, as the weights), and the local compliance between it and the tip's (the header's
  // formulas).
  double moment = 0;
  for (int k = 0; k < fp.count; ++k) {
    const Vec<dim> d = rest.col(fp.node[static_cast<std::size_t>(k)]) - rest_mean;
    moment += fp.weight[static_cast<std::size_t>(k)] * (d - n * n.dot(d)).squaredNorm();
  }
  const double spread = std::sqrt((dim == 3 ? 2.0 : 3.0) * moment);
  if (m_soft > 0 && spread > m_radius)
    fp.compliance = dim == 3 ? m_soft * (1.0 / m_radius - 1.0 / spread) : m_soft * std::log(spread / m_radius);
  // The tip's face: the footprint's weighted mean along its normal, the proxy's place across it.
  c.proxy += c.normal * c.normal.dot(mean - c.proxy);
}

template class TipFootprint<2>;
template class TipFootprint<3>;

} // namespace vtb
