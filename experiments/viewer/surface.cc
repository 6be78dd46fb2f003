#include "surface.hh"

#include <algorithm>
#include <limits>
#include <map>

namespace vtb::viewer {

template <int dim> Surface<dim> make_surface(const Mesh<dim>& mesh) {
  Surface<dim> s;
  if constexpr (dim == 2) {
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const auto& cell = mesh.cells[static_cast<std::size_t>(c)];
      s.tris.push_back({cell[0], cell[1], cell[2]});
      s.owner.push_back(c);
    }
    s.edges = unique_edges(mesh);
    for (const auto& f : boundary_facets(mesh))
      for (int v : f) s.boundary_nodes.push_back(v);
  } else {
    // Faces seen once are the boundary; a positively oriented tet (a, b, c, d) has the
    // outward faces (b, c, d), (a, d, c), (a, b, d), (a, c, b).
    std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> once;
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const auto& t = mesh.cells[static_cast<std::size_t>(c)];
      const std::array<std::array<int, 3>, 4> faces = {
          {{t[1], t[2], t[3]}, {t[0], t[3], t[2]}, {t[0], t[1], t[3]}, {t[0], t[2], t[1]}}};
      for (const auto& f : faces) {
        std::array<int, 3> key = f;
        std::sort(key.begin(), key.end());
        const auto it = once.find(key);
        if (it == once.end())
          once.emplace(key, std::make_pair(c, f));
        else
          once.erase(it);
      }
    }
    std::map<std::array<int, 2>, int> edge_set;
    for (const auto& [key, v] : once) {
      s.tris.push_back(v.second);
      s.owner.push_back(v.first);
      for (int k = 0; k < 3; ++k) {
        const int a = v.second[static_cast<std::size_t>(k)], b = v.second[static_cast<std::size_t>((k + 1) % 3)];
        edge_set[{std::min(a, b), std::max(a, b)}] = 1;
      }
      for (int n : v.second) s.boundary_nodes.push_back(n);
    }
    for (const auto& [e, unused] : edge_set) s.edges.push_back(e);
  }
  std::sort(s.boundary_nodes.begin(), s.boundary_nodes.end());
  s.boundary_nodes.erase(std::unique(s.boundary_nodes.begin(), s.boundary_nodes.end()), s.boundary_nodes.end());
  return s;
}

template <int dim>
int nearest_of(const std::vector<int>& candidates, const Mesh<dim>& mesh, const Nodal<dim>& u, const Vec<dim>& p) {
  int best = -1;
  double d = std::numeric_limits<double>::infinity();
  for (int i : candidates) {
    const double di = (mesh.points.col(i) + u.col(i) - p).squaredNorm();
    if (di < d) {
      d = di;
      best = i;
    }
  }
  return best;
}

template Surface<2> make_surface<2>(const Mesh<2>&);
template Surface<3> make_surface<3>(const Mesh<3>&);
template int nearest_of<2>(const std::vector<int>&, const Mesh<2>&, const Nodal<2>&, const Vec<2>&);
template int nearest_of<3>(const std::vector<int>&, const Mesh<3>&, const Nodal<3>&, const Vec<3>&);

} // namespace vtb::viewer
