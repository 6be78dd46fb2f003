#include "vtb/meshes/mesh.hh"

#include "vtb/base/input_error.hh"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>

namespace vtb {

template <int dim> double signed_measure(const Mesh<dim>& mesh, const typename Mesh<dim>::Cell& cell) {
  Eigen::Matrix<double, dim, dim> d;
  for (int k = 0; k < dim; ++k) d.col(k) = mesh.points.col(cell[k + 1]) - mesh.points.col(cell[0]);
  return d.determinant() / (dim == 2 ? 2.0 : 6.0);
}

template <int dim> double facet_measure(const Mesh<dim>& mesh, const typename Mesh<dim>::Facet& f) {
  if constexpr (dim == 2) {
    return (mesh.points.col(f[1]) - mesh.points.col(f[0])).norm();
  } else {
    const Eigen::Vector3d a = mesh.points.col(f[1]) - mesh.points.col(f[0]);
    const Eigen::Vector3d b = mesh.points.col(f[2]) - mesh.points.col(f[0]);
    return 0.5 * a.cross(b).norm();
  }
}

template <int dim> std::vector<std::array<int, 2>> unique_edges(const Mesh<dim>& mesh) {
  std::vector<std::array<int, 2>> edges;
  edges.reserve(mesh.cells.size() * (dim == 2 ? 3 : 6));
  for (const auto& c : mesh.cells)
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b) edges.push_back({std::min(c[a], c[b]), std::max(c[a], c[b])});
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

template <int dim> std::vector<typename Mesh<dim>::Facet> boundary_facets(const Mesh<dim>& mesh) {
  using Facet = typename Mesh<dim>::Facet;
  // Facet k of a cell is the cell without vertex k, ordered so that it is outward oriented
  // for a positively oriented cell.
  std::vector<std::pair<Facet, Facet>> all; // (sorted key, oriented facet)
  all.reserve(mesh.cells.size() * (dim + 1));
  for (const auto& c : mesh.cells) {
    for (int k = 0; k <= dim; ++k) {
      Facet f{};
      if constexpr (dim == 2) {
        f = {c[(k + 1) % 3], c[(k + 2) % 3]};
      } else {
        static constexpr int opp[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
        f = {c[opp[k][0]], c[opp[k][1]], c[opp[k][2]]};
      }
      Facet key = f;
      std::sort(key.begin(), key.end());
      all.push_back({key, f});
    }
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Facet> out;
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i + 1;
    while (j < all.size() && all[j].first == all[i].first) ++j;
    if (j - i == 1) out.push_back(all[i].second);
    i = j;
  }
  return out;
}

template <int dim> double bounding_diagonal(const Mesh<dim>& mesh) {
  if (mesh.num_nodes() == 0) return 0.0;
  return (mesh.points.rowwise().maxCoeff() - mesh.points.rowwise().minCoeff()).norm();
}

template <int dim> int check_and_orient(Mesh<dim>& mesh) {
  const int n = mesh.num_nodes();
  const std::string& src = mesh.source;
  if (n == 0) throw InputError(src + ": mesh has no nodes");
  if (mesh.cells.empty()) throw InputError(src + ": mesh has no " + (dim == 2 ? "triangles" : "tetrahedra"));
  for (int i = 0; i < n; ++i)
    if (!mesh.points.col(i).allFinite())
      throw InputError(src + ": node " + std::to_string(i) + " has a non-finite coordinate");
  const double h = bounding_diagonal(mesh);
  if (!(h > 0)) throw InputError(src + ": all nodes coincide");
  // A cell is degenerate when its measure is tiny against its own edge lengths.
  std::vector<char> used(static_cast<std::size_t>(n), 0);
  int flipped = 0;
  std::set<typename Mesh<dim>::Cell> seen;
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    auto& cell = mesh.cells[c];
    const std::string name = src + ": cell " + std::to_string(c);
    for (int v : cell)
      if (v < 0 || v >= n)
        throw InputError(name + " refers to node " + std::to_string(v) + ", out of range [0, " + std::to_string(n) +
                         ")");
    auto key = cell;
    std::sort(key.begin(), key.end());
    if (std::adjacent_find(key.begin(), key.end()) != key.end()) throw InputError(name + " repeats a vertex");
    if (!seen.insert(key).second) throw InputError(name + " duplicates an earlier cell");
    double lmax = 0;
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b)
        lmax = std::max(lmax, (mesh.points.col(cell[a]) - mesh.points.col(cell[b])).norm());
    const double vol = signed_measure(mesh, cell);
    if (!(std::abs(vol) > 1e-12 * std::pow(lmax, dim)))
      throw InputError(name + " has zero " + (dim == 2 ? "area" : "volume") + " (degenerate)");
    if (vol < 0) {
      std::swap(cell[0], cell[1]);
      ++flipped;
    }
    for (int v : cell) used[static_cast<std::size_t>(v)] = 1;
  }
  for (int i = 0; i < n; ++i)
    if (!used[static_cast<std::size_t>(i)])
      throw InputError(src + ": node " + std::to_string(i) + " belongs to no cell");
  return flipped;
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template double signed_measure<D>(const Mesh<D>&, const Mesh<D>::Cell&);                                             \
  template double facet_measure<D>(const Mesh<D>&, const Mesh<D>::Facet&);                                             \
  template std::vector<std::array<int, 2>> unique_edges<D>(const Mesh<D>&);                                            \
  template std::vector<Mesh<D>::Facet> boundary_facets<D>(const Mesh<D>&);                                             \
  template double bounding_diagonal<D>(const Mesh<D>&);                                                                \
  template int check_and_orient<D>(Mesh<D>&);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

} // namespace vtb
