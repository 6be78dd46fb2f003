#include "vtb/springs/force_jacobian.hh"

#include <algorithm>
#include <array>
#include <stdexcept>
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
  for_each_cell_block(net.volume, net.rest, u, clamp_compression,
                      [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>& D) {
                        const int i = net.volume.cell[static_cast<std::size_t>(c)][x];
                        const int j = net.volume.cell[static_cast<std::size_t>(c)][y];
                        for (int p = 0; p < dim; ++p)
                          for (int q = 0; q < dim; ++q) {
                            tk.emplace_back(dim * i + p, dim * j + q, K(p, q));
                            td.emplace_back(dim * i + p, dim * j + q, D(p, q));
                          }
                      });
  if (!clamp_compression)
    for_each_nodal_correction(net.volume, net.rest, u, [&](int i, int j, const Mat<dim>& K, const Mat<dim>& D) {
      for (int p = 0; p < dim; ++p)
        for (int q = 0; q < dim; ++q) {
          tk.emplace_back(dim * i + p, dim * j + q, K(p, q));
          td.emplace_back(dim * i + p, dim * j + q, D(p, q));
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

template <int dim>
Eigen::SparseMatrix<double> free_block_pattern(const SpringNetwork<dim>& net, const std::vector<int>& free_index,
                                               int free_count, Blocks blocks, Stars stars) {
  // Each free node's free neighbours, itself included, in one array cut by start[] (counted,
  // then filled), sorted and made unique per node (parallel springs share a block).
  const auto nf = static_cast<std::size_t>(free_count);
  const auto ends = [&](int s) {
    const auto& e = net.edge[static_cast<std::size_t>(s)];
    return std::array<int, 2>{free_index[static_cast<std::size_t>(e[0])], free_index[static_cast<std::size_t>(e[1])]};
  };
  std::vector<int> start(nf + 1, 0);
  for (std::size_t a = 0; a < nf; ++a) start[a + 1] = 1;
  for (int s = 0; s < net.num_springs(); ++s)
    if (const auto [a, b] = ends(s); a >= 0 && b >= 0) {
      ++start[static_cast<std::size_t>(a) + 1];
      ++start[static_cast<std::size_t>(b) + 1];
    }
  // A nodal volume term's stars (Stars::exact, cv.node_star): each node's free star nodes.
  const CellVolumes<dim>& cv = net.volume;
  const bool with_stars = stars == Stars::exact && cv.nodal();
  const auto for_each_star_pair = [&](auto&& pair) {
    if (!with_stars) return;
    for (std::size_t n = 0; n + 1 < cv.node_star_start.size(); ++n)
      for (int i = cv.node_star_start[n]; i < cv.node_star_start[n + 1]; ++i)
        if (const int a = free_index[static_cast<std::size_t>(cv.node_star[static_cast<std::size_t>(i)])]; a >= 0)
          for (int j = cv.node_star_start[n]; j < cv.node_star_start[n + 1]; ++j)
            if (const int b = free_index[static_cast<std::size_t>(cv.node_star[static_cast<std::size_t>(j)])]; b >= 0)
              pair(a, b);
  };
  for_each_star_pair([&](int a, int) { ++start[static_cast<std::size_t>(a) + 1]; });
  for (std::size_t a = 0; a < nf; ++a) start[a + 1] += start[a];
  std::vector<int> near(static_cast<std::size_t>(start[nf])), fill(start.begin(), start.end() - 1);
  for (std::size_t a = 0; a < nf; ++a) near[static_cast<std::size_t>(fill[a]++)] = static_cast<int>(a);
  for (int s = 0; s < net.num_springs(); ++s)
    if (const auto [a, b] = ends(s); a >= 0 && b >= 0) {
      near[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
      near[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)]++)] = a;
    }
  for_each_star_pair([&](int a, int b) { near[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b; });
  Eigen::VectorXi per_column(dim * free_count);
  for (std::size_t a = 0; a < nf; ++a) {
    auto first = near.begin() + start[a];
    const auto last = near.begin() + start[a + 1];
    std::sort(first, last);
    if (blocks == Blocks::lower) { // the column's blocks from its own node on, moved to its start
      const auto self = std::lower_bound(first, last, static_cast<int>(a));
      std::copy(self, last, first);
      const auto kept = last - self;
      fill[a] = static_cast<int>(std::unique(first, first + kept) - first);
      per_column.template segment<dim>(dim * static_cast<Eigen::Index>(a)).setConstant(dim * fill[a]);
      continue;
    }
    fill[a] = static_cast<int>(std::unique(first, last) - first); // now: the node's count of blocks
    per_column.template segment<dim>(dim * static_cast<Eigen::Index>(a)).setConstant(dim * fill[a]);
  }
  Eigen::SparseMatrix<double> A(dim * free_count, dim * free_count);
  A.reserve(per_column);
  for (std::size_t a = 0; a < nf; ++a) // rows in increasing order within each column
    for (int q = 0; q < dim; ++q)
      for (int k = 0; k < fill[a]; ++k)
        for (int p = 0; p < dim; ++p)
          A.insert(dim * near[static_cast<std::size_t>(start[a] + k)] + p, dim * static_cast<int>(a) + q) = 0.0;
  A.makeCompressed();
  return A;
}

template <int dim>
void fill_free_stiffness(const SpringNetwork<dim>& net, const Nodal<dim>& u, const std::vector<int>& free_index,
                         bool clamp_compression, Eigen::SparseMatrix<double>& A, Blocks blocks) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  double* value = A.valuePtr();
  std::fill(value, value + A.nonZeros(), 0.0);
  for_each_jacobian_block(net, u, clamp_compression,
                          [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>&) {
                            const int a = free_index[static_cast<std::size_t>(i)];
                            const int b = free_index[static_cast<std::size_t>(j)];
                            if (a < 0 || b < 0 || (blocks == Blocks::lower && a < b)) return;
                            for (int q = 0; q < dim; ++q) {
                              const int col = dim * b + q;
                              const int* at = std::lower_bound(inner + outer[col], inner + outer[col + 1], dim * a);
                              for (int p = 0; p < dim; ++p) value[(at - inner) + p] -= sign * K(p, q);
                            }
                          });
  // The volume term's blocks (its cells' node pairs are springs: the same pattern).
  for_each_cell_block(
      net.volume, net.rest, u, clamp_compression, [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>&) {
        const int a = free_index[static_cast<std::size_t>(net.volume.cell[static_cast<std::size_t>(c)][x])];
        const int b = free_index[static_cast<std::size_t>(net.volume.cell[static_cast<std::size_t>(c)][y])];
        if (a < 0 || b < 0 || (blocks == Blocks::lower && a < b)) return;
        for (int q = 0; q < dim; ++q) {
          const int col = dim * b + q;
          const int* at = std::lower_bound(inner + outer[col], inner + outer[col + 1], dim * a);
          for (int p = 0; p < dim; ++p) value[(at - inner) + p] -= K(p, q);
        }
      });
  if (clamp_compression) return;
  for_each_nodal_correction(net.volume, net.rest, u, [&](int i, int j, const Mat<dim>& K, const Mat<dim>&) {
    const int a = free_index[static_cast<std::size_t>(i)], b = free_index[static_cast<std::size_t>(j)];
    if (a < 0 || b < 0 || (blocks == Blocks::lower && a < b)) return;
    for (int q = 0; q < dim; ++q) {
      const int col = dim * b + q;
      const int* at = std::lower_bound(inner + outer[col], inner + outer[col + 1], dim * a);
      if (at == inner + outer[col + 1] || *at != dim * a)
        throw std::logic_error("fill_free_stiffness: a nodal volume term needs a pattern with Stars::exact");
      for (int p = 0; p < dim; ++p) value[(at - inner) + p] -= K(p, q);
    }
  });
}

template <int dim>
Eigen::SparseMatrix<double> free_stiffness(const SpringNetwork<dim>& net, const Nodal<dim>& u,
                                           const std::vector<int>& free_index, int free_count, bool clamp_compression) {
  Eigen::SparseMatrix<double> A =
      free_block_pattern(net, free_index, free_count, Blocks::both, clamp_compression ? Stars::bound : Stars::exact);
  fill_free_stiffness(net, u, free_index, clamp_compression, A);
  return A;
}

template Eigen::SparseMatrix<double> free_block_pattern<2>(const SpringNetwork<2>&, const std::vector<int>&, int,
                                                           Blocks, Stars);
template Eigen::SparseMatrix<double> free_block_pattern<3>(const SpringNetwork<3>&, const std::vector<int>&, int,
                                                           Blocks, Stars);
template Eigen::SparseMatrix<double> free_stiffness<2>(const SpringNetwork<2>&, const Nodal<2>&,
                                                       const std::vector<int>&, int, bool);
template Eigen::SparseMatrix<double> free_stiffness<3>(const SpringNetwork<3>&, const Nodal<3>&,
                                                       const std::vector<int>&, int, bool);
template void fill_free_stiffness<2>(const SpringNetwork<2>&, const Nodal<2>&, const std::vector<int>&, bool,
                                     Eigen::SparseMatrix<double>&, Blocks);
template void fill_free_stiffness<3>(const SpringNetwork<3>&, const Nodal<3>&, const std::vector<int>&, bool,
                                     Eigen::SparseMatrix<double>&, Blocks);
template ForceJacobians<2> force_jacobians<2>(const SpringNetwork<2>&, const Nodal<2>&, bool);
template ForceJacobians<3> force_jacobians<3>(const SpringNetwork<3>&, const Nodal<3>&, bool);

} // namespace vtb
