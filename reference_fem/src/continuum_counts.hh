#pragma once
// The sizes of a simplex mesh's P2 space, before and after uniform refinements, counted without
// building it: the continuum ladder's budget (continuum.cc) and continuum_first_dofs
// (continuum_size.cc, which the springs' checks call without loading deal.II).
#include "vtb/meshes/mesh.hh"

#include <algorithm>
#include <array>
#include <set>

namespace vtb::fem {

/// Vertices, edges, faces and cells of a simplex mesh, and the counts after one uniform
/// refinement (a triangle into 4; a tetrahedron into 8, one new interior edge each).
struct Counts {
  double v = 0, e = 0, f = 0, c = 0;
  Counts refined(int dim) const {
    if (dim == 2) return {v + e, 2 * e + 3 * c, 4 * c, 4 * c};
    return {v + e, 2 * e + 3 * f + c, 4 * f + 8 * c, 8 * c};
  }
  double p2_dofs(int dim) const { return dim * (v + e); }
};

template <int dim> Counts counts(const Mesh<dim>& mesh) {
  std::set<std::array<int, 2>> edges;
  std::set<std::array<int, 3>> faces;
  for (const auto& cell : mesh.cells) {
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b) edges.insert({std::min(cell[a], cell[b]), std::max(cell[a], cell[b])});
    if constexpr (dim == 3)
      for (int skip = 0; skip < 4; ++skip) {
        std::array<int, 3> f{};
        int k = 0;
        for (int a = 0; a < 4; ++a)
          if (a != skip) f[static_cast<std::size_t>(k++)] = cell[a];
        std::sort(f.begin(), f.end());
        faces.insert(f);
      }
  }
  return {static_cast<double>(mesh.num_nodes()), static_cast<double>(edges.size()),
          static_cast<double>(dim == 2 ? mesh.num_cells() : static_cast<int>(faces.size())),
          static_cast<double>(mesh.num_cells())};
}

} // namespace vtb::fem
