#include "vtb/solvers/tensor_filter.hh"

#include "mismatch_kernel.hh"
#include "polar_kernel.hh"

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

// The tensor filter's node rotations: each node's from the polar decomposition of its springs'
// deformation, how far they turned since the solve's frame, and the neighbourhoods' scales.
namespace vtb {

template <int dim> void TensorFilter<dim>::rotations(const Nodal<dim>& u) {
  ++m_turns;
  const auto& net = m_model.net;
  // A_i = sum over i's springs (x_j - x_i)(X_j - X_i)^T, gathered node by node so that the
  // sum stays in registers (scattered spring by spring, each add waited on the previous
  // one's store to the same node); the rest vectors X_j - X_i are read in order (m_adj_rest).
  // In 2D the rotation needs only a = A00 + A11 = sum d . D and b = A10 - A01 = sum D x d:
  // summed spring by spring, then normalised in a pass of their own (turn_rotations).
  if constexpr (dim == 2) {
    // (d . D, D x d) is the same from both ends (d and D change sign together): made once per
    // spring, with |d|^2 |D|^2 for the scan, and added to both ends' sums (spring_turns; the
    // step makes them in its force pass instead, prepare_turned).
    spring_turns(net, u, turns());
    turn_rotations();
  }
  if constexpr (dim == 3) {
    const int n = net.num_nodes();
    for (int i = 0; i < n; ++i) {
      const int begin = net.adj_ptr[static_cast<std::size_t>(i)];
      const int end = net.adj_ptr[static_cast<std::size_t>(i) + 1];
      const auto ui = u.col(i);
      Mat<dim> A = Mat<dim>::Zero();
      for (int p = begin; p < end; ++p) {
        const Vec<dim> d = m_adj_rest.col(p) + u.col(net.adj_node[static_cast<std::size_t>(p)]) - ui;
        A.noalias() += d * m_adj_ref.col(p).transpose();
      }
      Eigen::Map<Mat<dim>> scaled(&m_polar_a[9 * static_cast<std::size_t>(i)]);
      scaled = A * m_adj_scale[static_cast<std::size_t>(i)];
    }
    // The polar factors, four nodes per vector (detail::polar_rotations).
    detail::polar_rotations(n, m_polar_a.data(), m_rotation.data()->data(), m_polar_ok.data());
    for (int i = 0; i < n; ++i) {
      Mat<dim>& R = m_rotation[static_cast<std::size_t>(i)];
      if (!m_polar_ok[static_cast<std::size_t>(i)]) { // an inverted or flat neighbourhood: the SVD decides
        const Mat<dim> A = Eigen::Map<const Mat<dim>>(&m_polar_a[9 * static_cast<std::size_t>(i)]);
        const Eigen::JacobiSVD<Mat<dim>> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Mat<dim> U = svd.matrixU();
        if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(dim - 1) *= -1;
        R = U * svd.matrixV().transpose();
      }
      if (!R.allFinite()) R.setIdentity(); // a non-finite state: the run's watch stops it
    }
  }
}

template <int dim> SpringTurns TensorFilter<dim>::turns() {
  static_assert(dim == 2 || dim == 3);
  if constexpr (dim == 2) return SpringTurns{m_spring_ref.data(), &m_pq(0, 0), &m_pq(0, 1), &m_polar};
  return SpringTurns{nullptr, nullptr, nullptr, nullptr};
}

template <int dim> void TensorFilter<dim>::turn_rotations() {
  ++m_turns;
  if constexpr (dim == 2) {
    const auto& net = m_model.net;
    // The rotation nearest to A (polar part) in closed form: its angle is that of (a, b), so
    // (cos, sin) = (a, b) / |(a, b)| (no atan2), in one vector loop without the divider;
    // identity where (a, b) is zero or not finite (detail::unit_pairs).
    const int n = net.num_nodes();
    detail::unit_pairs(n, m_polar.data());
  }
}

template <int dim>
void TensorFilter<dim>::scale_neighbourhoods(const Nodal<dim>& ref, std::vector<double>& scale) const {
  if constexpr (dim == 3) {
    const auto& net = m_model.net;
    for (int i = 0; i < net.num_nodes(); ++i) {
      double trace = 0;
      for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p)
        trace += ref.col(p).squaredNorm();
      scale[static_cast<std::size_t>(i)] = trace > 0 ? 3 / trace : 1.0;
    }
  }
}

template <int dim> void TensorFilter<dim>::turn_out(double dt, Nodal<dim>& dv) const {
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<int>(free.size());
  const double* __restrict y = m_rhs.data();
  const int* __restrict at = m_index.data();
  double* __restrict out = dv.data();
  for (int a = 0; a < nf; ++a) {
    const Vec<dim> x = dt * (rotation(free[static_cast<std::size_t>(a)]) * Eigen::Map<const Vec<dim>>(y + at[a * dim]));
    for (int p = 0; p < dim; ++p) out[a * dim + p] = x[p];
  }
}

template void TensorFilter<2>::rotations(const Nodal<2>&);
template void TensorFilter<2>::turn_out(double, Nodal<2>&) const;
template SpringTurns TensorFilter<2>::turns();
template void TensorFilter<2>::turn_rotations();
template void TensorFilter<2>::scale_neighbourhoods(const Nodal<2>&, std::vector<double>&) const;
template void TensorFilter<3>::rotations(const Nodal<3>&);
template void TensorFilter<3>::turn_out(double, Nodal<3>&) const;
template SpringTurns TensorFilter<3>::turns();
template void TensorFilter<3>::turn_rotations();
template void TensorFilter<3>::scale_neighbourhoods(const Nodal<3>&, std::vector<double>&) const;

} // namespace vtb
