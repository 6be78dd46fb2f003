#pragma once
// Internal to reference_fem: what the serial and the distributed solvers share: the
// triangulation of a scene's mesh, the material's Lame constants, the element matrices, the
// rule for support points on a support's facets, the strain measure of the summary, and a
// level's answer by position for the next refinement (LevelAnswer, below).

#include "vtb/problem/problem.hh"

#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/numerics/rtree.h>

#include <Eigen/Dense>

#include <algorithm>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

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
void make_triangulation(const Problem<dim>& m_model, int refinements, dealii::Triangulation<dim>& m_tria,
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

/// Lame constants (lambda, mu); plane stress in 2D replaces lambda by
/// 2 lambda mu / (lambda + 2 mu) = E nu / (1 - nu^2).
template <int dim> std::pair<double, double> lame(const MaterialDesc& m) {
  const double E = m.young_modulus, nu = m.poisson_ratio;
  return {dim == 2 ? E * nu / (1 - nu * nu) : E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))};
}

/// Element stiffness k and consistent mass m on the cell fev was reinit'ed on, times the
/// thickness in 2D: (lambda div u div w + mu (grad u + grad u^T) : grad w), component form
/// (step-8), and rho u . w.
template <int dim>
void element_matrices(const dealii::FEValues<dim>& fev, const dealii::FESystem<dim>& fe, const MaterialDesc& mat,
                      dealii::FullMatrix<double>& k, dealii::FullMatrix<double>& m) {
  const auto [lambda, mu] = lame<dim>(mat);
  const double t = dim == 2 ? mat.thickness : 1.0;
  const unsigned int nd = fe.n_dofs_per_cell();
  k = 0;
  m = 0;
  for (unsigned int q = 0; q < fev.n_quadrature_points; ++q)
    for (unsigned int i = 0; i < nd; ++i) {
      const unsigned int ci = fe.system_to_component_index(i).first;
      for (unsigned int j = 0; j < nd; ++j) {
        const unsigned int cj = fe.system_to_component_index(j).first;
        const double jxw = fev.JxW(q) * t;
        k(i, j) += (fev.shape_grad(i, q)[ci] * fev.shape_grad(j, q)[cj] * lambda +
                    fev.shape_grad(i, q)[cj] * fev.shape_grad(j, q)[ci] * mu +
                    (ci == cj ? fev.shape_grad(i, q) * fev.shape_grad(j, q) * mu : 0.0)) *
                   jxw;
        if (ci == cj) m(i, j) += mat.density * fev.shape_value(i, q) * fev.shape_value(j, q) * jxw;
      }
    }
}

/// Whether point p lies on facet f of the mesh (within tol): a barycentric test on the
/// segment (2D) or triangle (3D).
template <int dim>
bool on_facet(const Mesh<dim>& mesh, const dealii::Point<dim>& p, const std::array<int, dim>& f, double tol) {
  const Eigen::Matrix<double, dim, 1> x = Eigen::Map<const Eigen::Matrix<double, dim, 1>>(p.begin_raw());
  const auto a = mesh.points.col(f[0]);
  Eigen::Matrix<double, dim, dim - 1> B;
  for (int k = 1; k < dim; ++k) B.col(k - 1) = mesh.points.col(f[static_cast<std::size_t>(k)]) - a;
  const Eigen::Matrix<double, dim - 1, 1> lam = (B.transpose() * B).ldlt().solve(B.transpose() * (x - a));
  if ((lam.array() < -1e-9).any() || lam.sum() > 1 + 1e-9) return false;
  return (a + B * lam - x).norm() <= tol;
}

/// The largest principal strain magnitude of the displacement u, at the centres of the cells
/// this process owns (all of them in a serial run).
template <int dim, class Vector>
double max_principal_strain(const dealii::Mapping<dim>& mapping, const dealii::FiniteElement<dim>& fe,
                            const dealii::DoFHandler<dim>& dofs, const Vector& u) {
  const dealii::QGaussSimplex<dim> centre(1);
  dealii::FEValues<dim> fev(mapping, fe, centre, dealii::update_gradients);
  std::vector<std::vector<dealii::Tensor<1, dim>>> grads(1, std::vector<dealii::Tensor<1, dim>>(dim));
  double worst = 0;
  for (const auto& cell : dofs.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fev.reinit(cell);
    fev.get_function_gradients(u, grads);
    Eigen::Matrix<double, dim, dim> g;
    for (int a = 0; a < dim; ++a)
      for (int b = 0; b < dim; ++b) g(a, b) = grads[0][static_cast<std::size_t>(a)][b];
    const Eigen::Matrix<double, dim, dim> eps = 0.5 * (g + g.transpose());
    worst = std::max(
        worst, Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, dim, dim>>(eps).eigenvalues().cwiseAbs().maxCoeff());
  }
  return worst;
}

// LevelAnswer: a solved level's displacement at points found by position, so that the next
// uniform refinement's Newton starts from it (nested iteration, docs/fem.md "Nested
// iteration"). The solved level evaluates its field at the points of barycentric coordinates in
// quarters of each cell: uniform refinement of a simplex puts the fine vertices at halves and
// the fine edges' midpoints at quarters, so every fine P1 or P2 support point is one of them and
// the coarse field is carried over exactly (a coarse P2 field is a fine P2 field). The points are
// found with deal.II's R-tree (boost::geometry).
template <int dim> class LevelAnswer {
public:
  /// `tolerance`: how near a queried point must lie to one of this level's points to be it (far
  /// below any mesh's spacing, far above the rounding of a point mapped from two cells).
  explicit LevelAnswer(double tolerance) : m_tolerance(tolerance) {}

  /// The displacement at p (a point shared by cells may be added once per cell).
  void add(const dealii::Point<dim>& p, const dealii::Tensor<1, dim>& value) {
    m_entries.emplace_back(p, static_cast<unsigned int>(m_value.size()));
    m_value.push_back(value);
  }

  /// Every rank's points on every rank, then filed by position.
  void gather(MPI_Comm comm) {
    int mpi = 0; // a plain run never initialises MPI (kelvin_voigt.cc's MpiScope)
    MPI_Initialized(&mpi);
    if (mpi && dealii::Utilities::MPI::n_mpi_processes(comm) > 1) {
      std::vector<double> mine;
      for (const auto& [p, k] : m_entries)
        for (int a = 0; a < 2 * dim; ++a) mine.push_back(a < dim ? p[a] : m_value[k][a - dim]);
      m_entries.clear(), m_value.clear();
      for (const auto& part : dealii::Utilities::MPI::all_gather(comm, mine))
        for (std::size_t k = 0; k + 2 * dim <= part.size(); k += 2 * dim) {
          dealii::Point<dim> p;
          dealii::Tensor<1, dim> v;
          for (int a = 0; a < dim; ++a) p[a] = part[k + a], v[a] = part[k + dim + a];
          add(p, v);
        }
    }
    m_tree = dealii::pack_rtree(m_entries);
  }

  /// The displacement at p, if a point of this level lies within the tolerance.
  std::optional<dealii::Tensor<1, dim>> at(const dealii::Point<dim>& p) const {
    std::vector<Entry> near;
    m_tree.query(boost::geometry::index::nearest(p, 1), std::back_inserter(near));
    if (near.empty() || near[0].first.distance(p) > m_tolerance) return std::nullopt;
    return m_value[near[0].second];
  }

private:
  using Entry = std::pair<dealii::Point<dim>, unsigned int>; ///< a point and its index in m_value
  double m_tolerance;
  std::vector<Entry> m_entries;
  std::vector<dealii::Tensor<1, dim>> m_value;
  dealii::RTree<Entry> m_tree;
};

} // namespace vtb::fem
