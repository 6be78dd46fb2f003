#include "vtb/haptics/contact2d.hh"

#include <algorithm>
#include <limits>
#include <map>

namespace vtb {

BoundaryContact::BoundaryContact(const Mesh2& mesh) {
  const auto facets = boundary_facets(mesh);
  std::map<int, int> starting_at; // node -> facet that starts there
  for (std::size_t f = 0; f < facets.size(); ++f) starting_at[facets[f][0]] = static_cast<int>(f);
  m_edges.reserve(facets.size());
  std::vector<int> order_of(facets.size(), -1);
  // Chain facets into loops (each boundary node starts exactly one outward facet).
  for (std::size_t start = 0; start < facets.size(); ++start) {
    if (order_of[start] >= 0) continue;
    const int first = static_cast<int>(m_edges.size());
    int f = static_cast<int>(start);
    while (order_of[static_cast<std::size_t>(f)] < 0) {
      order_of[static_cast<std::size_t>(f)] = static_cast<int>(m_edges.size());
      m_edges.push_back(facets[static_cast<std::size_t>(f)]);
      const auto it = starting_at.find(facets[static_cast<std::size_t>(f)][1]);
      if (it == starting_at.end()) break;
      f = it->second;
    }
    const int last = static_cast<int>(m_edges.size()) - 1;
    for (int e = first; e <= last; ++e) {
      m_next.push_back(e == last ? first : e + 1);
      m_prev.push_back(e == first ? last : e - 1);
    }
  }
}

bool BoundaryContact::inside(const Eigen::Vector2d& p, const Nodal<2>& x) const {
  // Winding number over the (outward, counter-clockwise) boundary loops.
  int wn = 0;
  for (const auto& e : m_edges) {
    const Eigen::Vector2d a = x.col(e[0]), b = x.col(e[1]);
    const double cross = (b.x() - a.x()) * (p.y() - a.y()) - (p.x() - a.x()) * (b.y() - a.y());
    if (a.y() <= p.y()) {
      if (b.y() > p.y() && cross > 0) ++wn;
    } else if (b.y() <= p.y() && cross < 0) {
      --wn;
    }
  }
  return wn != 0;
}

double BoundaryContact::closest_on(int e, const Eigen::Vector2d& p, const Nodal<2>& x, double& along) const {
  const Eigen::Vector2d a = x.col(m_edges[static_cast<std::size_t>(e)][0]);
  const Eigen::Vector2d d = x.col(m_edges[static_cast<std::size_t>(e)][1]) - a;
  along = std::clamp((p - a).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
  return (a + along * d - p).squaredNorm();
}

BoundaryContact::Result BoundaryContact::update(const Eigen::Vector2d& handle, const Nodal<2>& x, bool hold) {
  Result r;
  if (!(hold && m_last.touching) && !inside(handle, x)) {
    r.proxy = handle;
    m_last = r;
    return r;
  }
  int e = m_last.facet;
  if (!m_last.touching || e < 0) {
    // Contact begins: the globally closest boundary point (the handle has just crossed it).
    double best = std::numeric_limits<double>::infinity(), along = 0;
    for (int k = 0; k < static_cast<int>(m_edges.size()); ++k) {
      const double d = closest_on(k, handle, x, along);
      if (d < best) {
        best = d;
        e = k;
      }
    }
  }
  // Walk along the boundary from the current edge while the distance decreases: a local
  // minimum, which keeps the proxy on the side where contact began.
  double along = 0, d = closest_on(e, handle, x, along);
  for (int steps = 0; steps < static_cast<int>(m_edges.size()); ++steps) {
    double a_next = 0, a_prev = 0;
    const int n = m_next[static_cast<std::size_t>(e)], p = m_prev[static_cast<std::size_t>(e)];
    const double dn = closest_on(n, handle, x, a_next), dp = closest_on(p, handle, x, a_prev);
    if (dn < d && dn <= dp) {
      e = n, d = dn, along = a_next;
    } else if (dp < d) {
      e = p, d = dp, along = a_prev;
    } else {
      break;
    }
  }
  r.touching = true;
  r.facet = e;
  r.weights = {1 - along, along};
  const Eigen::Vector2d a = x.col(m_edges[static_cast<std::size_t>(e)][0]);
  r.proxy = a + along * (Eigen::Vector2d(x.col(m_edges[static_cast<std::size_t>(e)][1])) - a);
  m_last = r;
  return r;
}

} // namespace vtb
