#include "vtb/springs/force_jacobian.hh"

#include <vector>

namespace vtb {

template <int dim>
ForceJacobians<dim> force_jacobians(const SpringNetwork<dim>& net, const Nodal<dim>& u, bool clamp_compression) {
  const int n = dim * net.num_nodes();
  std::vector<Eigen::Triplet<double>> tk, td;
  tk.reserve(static_cast<std::size_t>(net.num_springs()) * 4 * dim * dim);
  td.reserve(tk.capacity() + static_cast<std::size_t>(n));
  for_each_jacobian_block(net, u, clamp_compression,
                          [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
                            for (int p = 0; p < dim; ++p)
                              for (int q = 0; q < dim; ++q) {
                                tk.emplace_back(dim * i + p, dim * j + q, sign * K(p, q));
                                td.emplace_back(dim * i + p, dim * j + q, sign * D(p, q));
                              }
                          });
  for (int i = 0; i < net.num_nodes(); ++i)
    for (int p = 0; p < dim; ++p) td.emplace_back(dim * i + p, dim * i + p, -net.mass_damping * net.mass[i]);
  ForceJacobians<dim> J;
  J.K.resize(n, n);
  J.D.resize(n, n);
  J.K.setFromTriplets(tk.begin(), tk.end());
  J.D.setFromTriplets(td.begin(), td.end());
  return J;
}

template ForceJacobians<2> force_jacobians<2>(const SpringNetwork<2>&, const Nodal<2>&, bool);
template ForceJacobians<3> force_jacobians<3>(const SpringNetwork<3>&, const Nodal<3>&, bool);

} // namespace vtb
