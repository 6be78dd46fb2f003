#pragma once
// Internal to reference_fem: the triangulation of a scene's mesh, shared by the serial and
// the distributed solvers.

#include "vtb/core/model.hh"

#include <deal.II/grid/tria.h>

#include <algorithm>
#include <map>
#include <set>

namespace vtb::fem {

template <int dim> dealii::Point<dim> to_point(const Eigen::Matrix<double, dim, 1>& x) {
  dealii::Point<dim> p;
  for (int a = 0; a < dim; ++a) p[a] = x[a];
  return p;
}

/// The scene's mesh as a deal.II triangulation, refined `refinements` times; boundary facets
/// of traction loads get a boundary id per combination of loads (ids survive refinement);
/// loads_of_id[id] lists the loads of id (id 0: none).
template <int dim>
void make_triangulation(const Model<dim>& m_model, int refinements, dealii::Triangulation<dim>& m_tria,
                        std::vector<std::vector<int>>& m_loads_of_id) {
  const Mesh<dim>& mesh = m_model.mesh;
  std::vector<dealii::Point<dim>> vertices(static_cast<std::size_t>(mesh.num_nodes()));
  for (int i = 0; i < mesh.num_nodes(); ++i) vertices[static_cast<std::size_t>(i)] = to_point<dim>(mesh.points.col(i));
  std::vector<dealii::CellData<dim>> cells(mesh.cells.size(), dealii::CellData<dim>(dim + 1));
  for (std::size_t c = 0; c < mesh.cells.size(); ++c)
    for (int k = 0; k <= dim; ++k)
      cells[c].vertices[static_cast<std::size_t>(k)] =
          static_cast<unsigned int>(mesh.cells[c][static_cast<std::size_t>(k)]);
  m_tria.create_triangulation(vertices, cells, dealii::SubCellData());

  std::map<std::array<int, dim>, std::set<int>> loads_of_facet;
  for (std::size_t l = 0; l < m_model.loads.size(); ++l)
    for (auto f : m_model.loads[l].facets) {
      std::sort(f.begin(), f.end());
      loads_of_facet[f].insert(static_cast<int>(l));
    }
  std::map<std::set<int>, dealii::types::boundary_id> m_load_ids; // set of loads on a facet -> id
  m_loads_of_id.assign(1, {});                                    // id 0: no load
  for (const auto& cell : m_tria.active_cell_iterators())
    for (const unsigned int face : cell->face_indices()) {
      if (!cell->face(face)->at_boundary()) continue;
      std::array<int, dim> key{};
      for (unsigned int v = 0; v < dim; ++v) key[v] = static_cast<int>(cell->face(face)->vertex_index(v));
      std::sort(key.begin(), key.end());
      const auto it = loads_of_facet.find(key);
      dealii::types::boundary_id id = 0;
      if (it != loads_of_facet.end()) {
        const auto [pos, inserted] =
            m_load_ids.emplace(it->second, static_cast<dealii::types::boundary_id>(m_loads_of_id.size()));
        if (inserted) m_loads_of_id.emplace_back(it->second.begin(), it->second.end());
        id = pos->second;
      }
      cell->face(face)->set_boundary_id(id);
    }
  if (refinements > 0) m_tria.refine_global(static_cast<unsigned int>(refinements));
}

} // namespace vtb::fem
