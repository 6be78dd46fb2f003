#include "vtb/solvers/explicit_euler.hh"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

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

namespace {
/// S = M^-1/2 K M^-1/2 on the free dofs, dense (the exact path: small meshes only).
template <int dim> Eigen::MatrixXd dense_scaled_stiffness(const Model<dim>& model) {
  const auto& net = model.net;
  const auto nf = static_cast<Eigen::Index>(model.free_nodes.size());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(nf * dim, nf * dim);
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const Mat<dim> K =
        spring_jacobian<dim>(net.rest.col(i), net.rest.col(j), net.rest_length[s], net.stiffness[s], true);
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    const double si = 1.0 / std::sqrt(net.mass[i]), sj = 1.0 / std::sqrt(net.mass[j]);
    if (a >= 0) S.template block<dim, dim>(a * dim, a * dim) += K * (si * si);
    if (b >= 0) S.template block<dim, dim>(b * dim, b * dim) += K * (sj * sj);
    if (a >= 0 && b >= 0) {
      S.template block<dim, dim>(a * dim, b * dim) -= K * (si * sj);
      S.template block<dim, dim>(b * dim, a * dim) -= K * (si * sj);
    }
  }
  // The volume term's rest blocks, -df_a/dx_b (cell_volumes.hh).
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_cell_block(net.volume, net.rest, rest, true, [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>&) {
    const int i = net.volume.cell[static_cast<std::size_t>(c)][x], j = net.volume.cell[static_cast<std::size_t>(c)][y];
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    if (a >= 0 && b >= 0) S.template block<dim, dim>(a * dim, b * dim) -= K / std::sqrt(net.mass[i] * net.mass[j]);
  });
  return S;
}
} // namespace

template <int dim> double max_omega_squared(const Model<dim>& model, bool exact) {
  // S = M^-1/2 K M^-1/2 on free dofs, K from the rest-state spring Jacobians.
  if (exact) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_scaled_stiffness(model), Eigen::EigenvaluesOnly);
    return es.eigenvalues().maxCoeff();
  }
  // Power iteration with S applied spring by spring from its dim x dim blocks: the blocks take
  // springs * dim^2 doubles (4.6 MB at 10k nodes in 3D) where the assembled S took 94 MB of
  // triplets and matrix at its peak.
  const auto& net = model.net;
  const auto nf = static_cast<Eigen::Index>(model.free_nodes.size());
  std::vector<Mat<dim>> block(static_cast<std::size_t>(net.num_springs()));
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    block[static_cast<std::size_t>(s)] =
        spring_jacobian<dim>(net.rest.col(i), net.rest.col(j), net.rest_length[s], net.stiffness[s], true);
  }
  // The volume term's rest stiffness k_c g g^T (g: the cell's rest gradients, b_a), rank one per
  // cell, and its shear part's Gauss-Newton blocks m_c (b_a . b_b) I (the bound of
  // dense_scaled_stiffness, which takes the same blocks).
  std::vector<Eigen::Matrix<double, dim, dim + 1>> grad(static_cast<std::size_t>(net.volume.size()));
  for (std::size_t c = 0; c < grad.size(); ++c) grad[c] = rest_gradients<dim>(net.volume.rest_inverse[c]);
  Eigen::VectorXd scale(net.mass.size()); // 1/sqrt(m) per node
  for (Eigen::Index i = 0; i < scale.size(); ++i) scale[i] = 1.0 / std::sqrt(net.mass[i]);
  Nodal<dim> x(dim, nf), y(dim, nf);
  const Eigen::VectorXd seed = Eigen::VectorXd::LinSpaced(nf * dim, 1.0, 2.0).array().sin();
  x = Eigen::Map<const Nodal<dim>>(seed.data(), dim, nf);
  double lambda = 0;
  for (int it = 0; it < 400; ++it) {
    y.setZero();
    for (int s = 0; s < net.num_springs(); ++s) {
      const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
      const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
      // The spring's stretch in scaled coordinates (a fixed end does not move), then its force.
      Vec<dim> d = Vec<dim>::Zero();
      if (a >= 0) d += scale[i] * x.col(a);
      if (b >= 0) d -= scale[j] * x.col(b);
      const Vec<dim> f = block[static_cast<std::size_t>(s)] * d;
      if (a >= 0) y.col(a) += scale[i] * f;
      if (b >= 0) y.col(b) -= scale[j] * f;
    }
    for (int c = 0; c < net.volume.size(); ++c) {
      const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
      const auto& g = grad[static_cast<std::size_t>(c)];
      double rate = 0; // g . (M^-1/2 x) over the cell's free nodes
      for (int p = 0; p <= dim; ++p) {
        const int a = model.free_index[static_cast<std::size_t>(cell[p])];
        if (a >= 0) rate += scale[cell[p]] * g.col(p).dot(x.col(a));
      }
      rate *= net.volume.stiffness[c];
      for (int p = 0; p <= dim; ++p) {
        const int a = model.free_index[static_cast<std::size_t>(cell[p])];
        if (a >= 0) y.col(a) += (scale[cell[p]] * rate) * g.col(p);
      }
      if (net.volume.has_shear()) {    // its shear part's m_c (b_a . b_b) I (the same blocks as above)
        Mat<dim> B = Mat<dim>::Zero(); // sum_b (M^-1/2 x)_b b_b^T, then B b_a per node
        for (int p = 0; p <= dim; ++p) {
          const int a = model.free_index[static_cast<std::size_t>(cell[p])];
          if (a >= 0) B += (scale[cell[p]] * x.col(a)) * g.col(p).transpose();
        }
        B *= net.volume.shear[c];
        for (int p = 0; p <= dim; ++p) {
          const int a = model.free_index[static_cast<std::size_t>(cell[p])];
          if (a >= 0) y.col(a) += scale[cell[p]] * (B * g.col(p));
        }
      }
    }
    lambda = (x.array() * y.array()).sum() / x.squaredNorm();
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
