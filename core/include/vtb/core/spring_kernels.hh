#pragma once
/// \file
/// Kernels of one Voigt element (a linear spring in parallel with a dashpot along the
/// edge), as free functions so that tests can check them alone. Hot loops inline them.

#include "vtb/core/nodal.hh"

#include <cmath>

namespace vtb {

/// Force on node i from the Voigt element (i, j):
///   f_i = [ k (l - L0) + c (v_j - v_i) . n ] n,   n = (x_j - x_i) / l,   l = |x_j - x_i|.
/// Node j receives -f_i. The dashpot acts along the element (a true Voigt unit), so the pair
/// carries no torque and a rigid rotation is not damped. Returns zero for l = 0.
template <int dim>
inline Vec<dim> voigt_force(const Vec<dim>& xi, const Vec<dim>& xj, const Vec<dim>& vi, const Vec<dim>& vj,
                            double rest_length, double k, double c) {
  const Vec<dim> d = xj - xi;
  const double l2 = d.squaredNorm();
  if (!(l2 > 0)) return Vec<dim>::Zero();
  // One square root and one division per element (n = d / l would divide dim times).
  const double inv_l = 1.0 / std::sqrt(l2);
  return ((k * (l2 * inv_l - rest_length) + c * inv_l * d.dot(vj - vi)) * inv_l) * d;
}

/// Stiffness block of a spring, K = d f_i / d x_j = -d f_i / d x_i:
///   K = k [ n n^T + (1 - L0 / l) (I - n n^T) ].
/// With `clamp_compression`, the transverse factor is max(0, 1 - L0/l), which keeps the
/// assembled matrix positive semidefinite for a compressed spring (Choi and Ko 2002).
template <int dim>
inline Mat<dim> spring_jacobian(const Vec<dim>& xi, const Vec<dim>& xj, double rest_length, double k,
                                bool clamp_compression) {
  const Vec<dim> d = xj - xi;
  const double l = d.norm();
  if (!(l > 0)) return k * Mat<dim>::Identity();
  const Vec<dim> n = d / l;
  const Mat<dim> nn = n * n.transpose();
  double t = 1.0 - rest_length / l;
  if (clamp_compression && t < 0) t = 0;
  return k * (nn + t * (Mat<dim>::Identity() - nn));
}

/// Damping block of the dashpot, d f_i / d v_j = c n n^T (the dependence of n on x is the
/// usual omitted term).
template <int dim> inline Mat<dim> dashpot_jacobian(const Vec<dim>& xi, const Vec<dim>& xj, double c) {
  const Vec<dim> d = xj - xi;
  const double l = d.norm();
  if (!(l > 0)) return Mat<dim>::Zero();
  const Vec<dim> n = d / l;
  return c * n * n.transpose();
}

} // namespace vtb
