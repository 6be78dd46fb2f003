#pragma once
/// \file
/// Kernels of one Voigt element (a linear spring in parallel with a dashpot along the
/// edge), as free functions so that tests can check them alone. Hot loops inline them.

#include "vtb/linalg/nodal.hh"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace vtb {

/// 1 / sqrt(x) for x > 0 without the divider (which a square root and a division share, and
/// which bounds a scalar spring loop): the exponent-halving seed (relative error < 3.5 %), then
/// four Newton steps y <- y (3/2 - x y^2 / 2), each of which squares the relative error
/// (3.5e-2 -> 1.8e-3 -> 4.7e-6 -> 3.3e-11 -> 1e-21), so round-off is what remains: within
/// 1.3 ulp of the exact value (1/sqrt as two rounded operations: 0.75 ulp). Only adds, multiplies
/// and integer operations, so a loop of it vectorises, and in the same order on every machine.
inline double newton_inverse_sqrt(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits = 0x5FE6EB50C7B537A9ull - (bits >> 1);
  double y;
  std::memcpy(&y, &bits, sizeof bits);
  const double half = 0.5 * x;
  for (int it = 0; it < 4; ++it) y = y * (1.5 - half * y * y);
  return y;
}

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
