// The Kelvin-Voigt reference's static answers to P1 body forces: the continuum's answers to a
// spring fit's training loads (continuum.hh). A member of KelvinVoigtProblem
// (kelvin_voigt_problem.hh), instantiated for the serial backend.
#include "kelvin_voigt_problem.hh"

#include <Eigen/LU>

namespace vtb::fem {

template <int dim, class Backend>
Eigen::MatrixXd KelvinVoigtProblem<dim, Backend>::body_force_answers(const Eigen::MatrixXd& g) {
  m_answers = true;
  m_backend.create(m_model, m_opt.refinements, *m_tria, m_loads_of_id);
  setup_dofs();
  setup_nodes();
  setup_constraints();
  choose_solvers();
  assemble();
  m_solver.factor(m_A0);
  // Each dof's value of the P1 field: its support point's barycentric coordinates in the scene's
  // cell it lies in (the level-0 ancestor of its cell; the triangulation's vertices are the
  // scene's nodes in order, grid.hh).
  const auto n = m_dofs.n_dofs();
  std::vector<std::array<double, dim + 1>> weight(n);
  std::vector<std::array<unsigned int, dim + 1>> node(n);
  std::vector<char> done(n, 0);
  std::vector<dof_t> local(m_fe.n_dofs_per_cell());
  for (const auto& cell : m_dofs.active_cell_iterators()) {
    auto coarse = typename dealii::Triangulation<dim>::cell_iterator(cell);
    while (coarse->level() > 0) coarse = coarse->parent();
    Eigen::Matrix<double, dim, dim> J;
    for (int a = 0; a < dim; ++a)
      for (int i = 0; i < dim; ++i)
        J(i, a) = coarse->vertex(static_cast<unsigned int>(a + 1))[i] - coarse->vertex(0)[i];
    const Eigen::Matrix<double, dim, dim> Jinv = J.inverse();
    cell->get_dof_indices(local);
    for (const dof_t d : local) {
      if (done[d]) continue;
      done[d] = 1;
      Eigen::Matrix<double, dim, 1> x;
      for (int i = 0; i < dim; ++i) x[i] = m_point[d][i] - coarse->vertex(0)[i];
      const Eigen::Matrix<double, dim, 1> lam = Jinv * x;
      weight[d][0] = 1 - lam.sum();
      node[d][0] = coarse->vertex_index(0);
      for (int a = 0; a < dim; ++a) {
        weight[d][static_cast<std::size_t>(a + 1)] = lam[a];
        node[d][static_cast<std::size_t>(a + 1)] = coarse->vertex_index(static_cast<unsigned int>(a + 1));
      }
    }
  }
  Eigen::MatrixXd out(g.rows(), g.cols());
  Vector field(n), rhs(n), u(n);
  for (Eigen::Index col = 0; col < g.cols(); ++col) {
    for (dof_t d = 0; d < n; ++d) {
      double v = 0;
      for (int k = 0; k <= dim; ++k)
        v += weight[d][static_cast<std::size_t>(k)] *
             g(dim * static_cast<Eigen::Index>(node[d][static_cast<std::size_t>(k)]) + m_comp[d], col);
      field[d] = v;
    }
    m_M.vmult(rhs, field); // the consistent mass carries the density (and the thickness in 2D)
    rhs /= m_mat.density;
    zero_prescribed(rhs);
    m_solver.solve(u, rhs);
    for (int v = 0; v < m_model.num_nodes(); ++v)
      for (int i = 0; i < dim; ++i)
        out(dim * v + i, col) = u[m_node[static_cast<std::size_t>(v) * dim + static_cast<std::size_t>(i)]];
  }
  return out;
}

template Eigen::MatrixXd KelvinVoigtProblem<2, SerialBackend<2>>::body_force_answers(const Eigen::MatrixXd&);
template Eigen::MatrixXd KelvinVoigtProblem<3, SerialBackend<3>>::body_force_answers(const Eigen::MatrixXd&);

} // namespace vtb::fem
