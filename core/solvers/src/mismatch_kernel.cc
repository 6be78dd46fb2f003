#include "mismatch_kernel.hh"

#include "vtb/linalg/vector_clones.hh"
#include "vtb/springs/spring_kernels.hh"

#include <cmath>
#include <limits>

namespace vtb::detail {

namespace {

/// Whether unit_pairs' vector loop scales a pair with a^2 + b^2 = x (false for NaN); `&`, not
/// `&&`, so that the loop has no branch.
inline bool scalable(double x) {
  return (x >= 1e-280) & (x < std::numeric_limits<double>::infinity());
}

} // namespace

VTB_VECTOR_CLONES void unit_pairs(int n, double* ab) {
  long odd = 0;
  for (int i = 0; i < n; ++i) {
    const double a = ab[2 * i], b = ab[2 * i + 1], x = a * a + b * b;
    const bool ok = scalable(x);
    const double inv = ok ? newton_inverse_sqrt(x) : 1.0;
    ab[2 * i] = a * inv;
    ab[2 * i + 1] = b * inv;
    odd |= !ok;
  }
  for (int i = 0; odd && i < n; ++i) { // the rare pairs the loop left as they were
    const double a = ab[2 * i], b = ab[2 * i + 1], x = a * a + b * b;
    if (scalable(x)) continue;
    const double inv = 1 / std::sqrt(x);
    const bool finite = std::isfinite(a * inv) && std::isfinite(b * inv);
    ab[2 * i] = finite ? a * inv : 1.0;
    ab[2 * i + 1] = finite ? b * inv : 0.0;
  }
}

VTB_VECTOR_CLONES void mismatch_sin2(int n, const double* p, const double* q, const double* w, const double* cx,
                                     const double* cy, const double* trigger, double* s2, bool& outgrown, bool& rare) {
  long out = 0, odd = 0;
  for (int s = 0; s < n; ++s) {
    const double cross = cy[s] * p[s] - cx[s] * q[s], dot = cx[s] * p[s] + cy[s] * q[s];
    const double den = w[s] * (cx[s] * cx[s] + cy[s] * cy[s]), cross2 = cross * cross;
    const bool ok = (dot > 0) & (den > 0); // false for NaN
    const double r = cross2 / den;
    s2[s] = ok ? r : 0.0;
    out |= cross2 > trigger[s] * den;
    odd |= !ok;
  }
  outgrown = out != 0;
  rare = odd != 0;
}

} // namespace vtb::detail
