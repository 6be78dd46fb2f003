#include "vtb/core/warped_filter.hh"

#include "vtb/core/force_jacobian.hh"

#include <Eigen/LU>
#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>

namespace vtb {

template <int dim> Eigen::SparseMatrix<double> tensor_filter_matrix(const Model<dim>& model, double dt) {
  const auto& net = model.net;
  const int nf = static_cast<int>(model.free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int a = 0; a < nf; ++a)
    for (int p = 0; p < dim; ++p)
      trip.emplace_back(a * dim + p, a * dim + p,
                        net.mass[model.free_nodes[static_cast<std::size_t>(a)]] * (1.0 + dt * net.mass_damping));
  // The shared assembly at rest: blocks k n n^T and c n n^T (-sign: stiffness signs).
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_jacobian_block(net, rest, false, [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    if (a < 0 || b < 0) return;
    const Mat<dim> B = -sign * (dt * D + dt * dt * K);
    for (int p = 0; p < dim; ++p)
      for (int q = 0; q < dim; ++q) trip.emplace_back(a * dim + p, b * dim + q, B(p, q));
  });
  Eigen::SparseMatrix<double> H(nf * dim, nf * dim);
  H.setFromTriplets(trip.begin(), trip.end());
  return H;
}

template <int dim>
WarpedFilter<dim>::WarpedFilter(const Model<dim>& model, double dt)
    : m_model(model), m_h(tensor_filter_matrix(model, dt)),
      m_rotation(static_cast<std::size_t>(model.num_nodes()), Mat<dim>::Identity()),
      m_rhs(static_cast<Eigen::Index>(model.free_nodes.size()) * dim, 1) {
  if (!m_h.factorize()) throw std::runtime_error("filtered (tensor): H is not positive definite");
}

template <int dim> void WarpedFilter<dim>::rotations(const Nodal<dim>& u) {
  const auto& net = m_model.net;
  for (int i = 0; i < net.num_nodes(); ++i) {
    Mat<dim> A = Mat<dim>::Zero();
    const Vec<dim> xi = net.rest.col(i) + u.col(i);
    for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p) {
      const int j = net.adj_node[static_cast<std::size_t>(p)];
      A += (net.rest.col(j) + u.col(j) - xi) * (net.rest.col(j) - net.rest.col(i)).transpose();
    }
    Mat<dim>& R = m_rotation[static_cast<std::size_t>(i)];
    if constexpr (dim == 2) {
      // The rotation nearest to A (polar part) in closed form.
      const double angle = std::atan2(A(1, 0) - A(0, 1), A(0, 0) + A(1, 1));
      R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    } else {
      const Eigen::JacobiSVD<Mat<dim>> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Mat<dim> U = svd.matrixU();
      if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(dim - 1) *= -1;
      R = U * svd.matrixV().transpose();
    }
    if (!R.allFinite()) R.setIdentity(); // a non-finite state: the run's watch stops it
  }
}

template <int dim>
void WarpedFilter<dim>::apply(const Nodal<dim>& u, const Nodal<dim>& force, double dt, Nodal<dim>& dv) {
  rotations(u);
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<int>(free.size());
  for (int a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    const Vec<dim> f = m_rotation[static_cast<std::size_t>(i)].transpose() * force.col(i);
    for (int p = 0; p < dim; ++p) m_rhs(m_h.ordered(a * dim + p), 0) = f[p];
  }
  m_h.solve_in_place(m_rhs);
  for (int a = 0; a < nf; ++a) {
    Vec<dim> x;
    for (int p = 0; p < dim; ++p) x[p] = m_rhs(m_h.ordered(a * dim + p), 0);
    dv.col(a) = dt * (m_rotation[static_cast<std::size_t>(free[static_cast<std::size_t>(a)])] * x);
  }
}

template class WarpedFilter<2>;
template class WarpedFilter<3>;
template Eigen::SparseMatrix<double> tensor_filter_matrix<2>(const Model<2>&, double);
template Eigen::SparseMatrix<double> tensor_filter_matrix<3>(const Model<3>&, double);

} // namespace vtb
