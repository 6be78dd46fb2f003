#pragma once
/// \file
/// The assembled Jacobians of the internal forces f(u, v) of `add_internal_forces`, over all
/// nodes: the reference that every solver's own (allocation-free, slot-based) assembly is
/// checked against in the tests, and what a precompute may factor.

#include "vtb/core/spring_network.hh"

#include <Eigen/SparseCore>

namespace vtb {

/// K = df/du and D = df/dv, dim n x dim n, node-major (row dim i + p is node i, axis p):
///   K: per spring the blocks -B on (i, i) and (j, j), +B on (i, j) and (j, i), with
///      B = spring_jacobian (its transverse term clamped at 0 under compression when
///      `clamp_compression`, as implicit Euler uses it);
///   D: the same pattern with dashpot_jacobian, minus gamma m I on the diagonal.
/// The dashpot's dependence on positions (through its direction) is omitted from K, as in
/// every solver here: K is exact at v = 0 or for undamped springs.
template <int dim> struct ForceJacobians { Eigen::SparseMatrix<double> K, D; };

template <int dim>
ForceJacobians<dim> force_jacobians(const SpringNetwork<dim>& net, const Nodal<dim>& u, bool clamp_compression);

} // namespace vtb
