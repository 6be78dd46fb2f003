#include "vtb/solvers/explicit_euler.hh"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>

namespace vtb {

template <int dim>
ExplicitEuler<dim>::ExplicitEuler(const Model<dim>& model, double dt)
    : Integrator<dim>(dt), m_model(model), m_force(dim, model.num_nodes()), m_ext(dim, model.num_nodes()) {}

template <int dim> void ExplicitEuler<dim>::step(State<dim>& s) {
  const double dt = this->dt();
  m_model.external_forces(s.t, m_ext);
  if (s.applied.cols() == m_ext.cols()) m_ext += s.applied;
  m_force = m_ext;
  add_internal_forces(m_model.net, s.u, s.v, m_force);
  for (int i : m_model.free_nodes) {
    s.v.col(i) += (dt / m_model.net.mass[i]) * m_force.col(i);
    s.u.col(i) += dt * s.v.col(i);
  }
  s.t += dt;
  m_model.apply_constraints(s.t, s.u, s.v);
}

template <int dim> double max_omega_squared(const Model<dim>& model, bool exact) {
  // S = M^-1/2 K M^-1/2 on free dofs, K from the rest-state spring Jacobians.
  const auto& net = model.net;
  const int nf = static_cast<int>(model.free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const Mat<dim> K =
        spring_jacobian<dim>(net.rest.col(i), net.rest.col(j), net.rest_length[s], net.stiffness[s], true);
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    const double si = 1.0 / std::sqrt(net.mass[i]), sj = 1.0 / std::sqrt(net.mass[j]);
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q) {
        if (a >= 0) trip.emplace_back(a * dim + p, a * dim + q, K(p, q) * si * si);
        if (b >= 0) trip.emplace_back(b * dim + p, b * dim + q, K(p, q) * sj * sj);
        if (a >= 0 && b >= 0) {
          trip.emplace_back(a * dim + p, b * dim + q, -K(p, q) * si * sj);
          trip.emplace_back(b * dim + p, a * dim + q, -K(p, q) * si * sj);
        }
      }
  }
  Eigen::SparseMatrix<double> S(nf * dim, nf * dim);
  S.setFromTriplets(trip.begin(), trip.end());
  if (exact) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(S), Eigen::EigenvaluesOnly);
    return es.eigenvalues().maxCoeff();
  }
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(nf * dim, 1.0, 2.0).array().sin();
  double lambda = 0;
  for (int it = 0; it < 400; ++it) {
    const Eigen::VectorXd y = S * x;
    lambda = x.dot(y) / x.squaredNorm();
    x = y / y.norm();
  }
  return lambda;
}

double explicit_critical_dt(double w2, double tau, double gamma) {
  const double b = gamma + tau * w2;
  return (-b + std::sqrt(b * b + 4.0 * w2)) / w2;
}

template class ExplicitEuler<2>;
template class ExplicitEuler<3>;
template double max_omega_squared<2>(const Model<2>&, bool);
template double max_omega_squared<3>(const Model<3>&, bool);

} // namespace vtb
