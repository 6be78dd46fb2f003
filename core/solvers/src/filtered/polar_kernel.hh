#pragma once
// The 3D tensor filter's rotations: the polar factors of the nodes' 3 x 3 matrices, four nodes
// per vector (tensor_filter.cc's rotations(); docs/performance.md item 16).

namespace vtb::detail {

/// For each of n matrices A_k (9 doubles each, column-major, one after the other) the rotation
/// R_k nearest to it (its polar factor) where det A_k > 0, by Newton's iteration X <- (g X +
/// (g X)^-T) / 2 with Higham's determinant scaling g = det(X)^(-1/3) while X is far from
/// orthogonal (change > 1e-4); X^-T = cof(X) / det(X) (the columns' cross products), so an
/// iteration is three cross products and one division. It converges quadratically: 5-7
/// iterations on matrices scaled to singular values near 1 (the caller's 3 / tr A_rest).
/// Stops at a change of 1e-15 (|R| = sqrt 3: round-off). Four matrices run in the lanes of one
/// vector until all four have converged (a lane that has stops changing). ok[k] = 0 where det
/// A_k <= 0 or not finite or it has not converged in 30 iterations (R_k then undefined: the
/// caller decides by an SVD).
void polar_rotations(int n, const double* A, double* R, unsigned char* ok);

/// About x^(-1/3) for x > 0 (within 4e-4 for 1e-200 < x < 1e200, cbrt outside): the
/// exponent divided by -3 in the bits, then two Newton steps y <- y (4 - x y^3) / 3. The
/// polar iteration's scaling needs no more (any g > 0 leaves the polar factor as it is, and
/// the scaling stops near convergence); libm's cbrt took a fifth of the 3D tensor step.
double approx_inverse_cbrt(double x);

} // namespace vtb::detail
