#pragma once
/// \file
/// The assembled Jacobians of the internal forces f(u, v) of `add_internal_forces`, over all
/// nodes: the reference that every solver's own (allocation-free, slot-based) assembly is
/// checked against in the tests, and what a precompute may factor.

#include "vtb/springs/spring_network.hh"

#include <Eigen/SparseCore>

namespace vtb {

/// The one assembly of the spring forces' Jacobian, shared by force_jacobians, implicit Euler,
/// CVODE and the filter's precompute: for each spring s = (i, j) at displacement u, its blocks
/// K_s = df_i/du_j (spring_jacobian; its transverse term clamped at 0 under compression when
/// `clamp_compression`) and D_s = df_i/dv_j (dashpot_jacobian); df_i/du_i = -K_s, and the same
/// with i and j swapped. Calls add(s, i, j, sign, K_s, D_s) for the four blocks (i, i, -1),
/// (j, j, -1), (i, j, +1), (j, i, +1) of every spring, in that order; the caller scatters them
/// into its own storage. Mass damping (-gamma m I on D's diagonal) is the caller's. Allocates
/// nothing.
template <int dim, class Add>
void for_each_jacobian_block(const SpringNetwork<dim>& net, const Nodal<dim>& u, bool clamp_compression, Add&& add) {
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const Vec<dim> xi = net.rest.col(i) + u.col(i), xj = net.rest.col(j) + u.col(j);
    const Mat<dim> K = spring_jacobian<dim>(xi, xj, net.rest_length[s], net.stiffness[s], clamp_compression);
    const Mat<dim> D = dashpot_jacobian<dim>(xi, xj, net.damping[s]);
    add(s, i, i, -1.0, K, D);
    add(s, j, j, -1.0, K, D);
    add(s, i, j, 1.0, K, D);
    add(s, j, i, 1.0, K, D);
  }
}

/// K = df/du and D = df/dv, dim n x dim n, node-major (row dim i + p is node i, axis p):
///   K: per spring the blocks -B on (i, i) and (j, j), +B on (i, j) and (j, i), with
///      B = spring_jacobian (its transverse term clamped at 0 under compression when
///      `clamp_compression`, as implicit Euler uses it);
///   D: the same pattern with dashpot_jacobian, minus gamma m I on the diagonal;
///   the volume term's blocks (exact when not `clamp_compression`, a nodal term's stars too).
/// The dashpot's dependence on positions (through its direction) is omitted from K, as in
/// every solver here: K is exact at v = 0 or for undamped springs.
template <int dim> struct ForceJacobians { Eigen::SparseMatrix<double> K, D; };

template <int dim>
ForceJacobians<dim> force_jacobians(const SpringNetwork<dim>& net, const Nodal<dim>& u, bool clamp_compression);

/// The pattern of the springs' Jacobian on the free dofs (free_index: node -> free index or -1,
/// free_count of them): a full dim x dim block for each free node and for each spring between two
/// free nodes, in both orders; values 0, compressed, a node's rows consecutive in each column.
/// Built in place, without triplets (a triplet list holds several times the matrix). The solvers' systems (implicit
/// Euler, CVODE's preconditioner) and the load check share it. `Blocks::lower` keeps a block
/// only where its row node is at or after its column node: the lower triangle a Cholesky
/// factorisation reads (CHOLMOD ignores the diagonal blocks' upper entries), half the memory
/// (the fit's matrix). `Stars::exact` adds, with a volume term averaged per node, a block for
/// each pair of nodes in one node's star (the exact Jacobian couples them; the bound that the
/// integrators take does not).
enum class Blocks { both, lower };
enum class Stars { bound, exact };
template <int dim>
Eigen::SparseMatrix<double> free_block_pattern(const SpringNetwork<dim>& net, const std::vector<int>& free_index,
                                               int free_count, Blocks blocks = Blocks::both,
                                               Stars stars = Stars::bound);

/// The springs' stiffness -K (clamp_compression as force_jacobians) at displacement u on the
/// free dofs, on free_block_pattern: the matrix of the load check's static solve.
template <int dim>
Eigen::SparseMatrix<double> free_stiffness(const SpringNetwork<dim>& net, const Nodal<dim>& u,
                                           const std::vector<int>& free_index, int free_count, bool clamp_compression);
/// free_stiffness's values written into A, a free_block_pattern of the same network and
/// free_index and `blocks` (the fit's assembly at each of its steps, allocation-free). Each
/// entry sums its springs' blocks in the springs' order, as setFromTriplets sums
/// force_jacobians' triplets: the same values to the bit. Unclamped, a nodal volume term's
/// exact blocks need a pattern with Stars::exact.
template <int dim>
void fill_free_stiffness(const SpringNetwork<dim>& net, const Nodal<dim>& u, const std::vector<int>& free_index,
                         bool clamp_compression, Eigen::SparseMatrix<double>& A, Blocks blocks = Blocks::both);

} // namespace vtb
