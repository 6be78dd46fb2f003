#pragma once
/// \file
/// The small vector types every part of vtb shares: a point or force in dim dimensions, a
/// dim x dim matrix, and a field with one column per node.

#include <Eigen/Core>

namespace vtb {

template <int dim> using Vec = Eigen::Matrix<double, dim, 1>;
template <int dim> using Mat = Eigen::Matrix<double, dim, dim>;
template <int dim> using Nodal = Eigen::Matrix<double, dim, Eigen::Dynamic>; ///< one column per node

} // namespace vtb
