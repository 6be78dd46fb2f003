#include "polar_kernel.hh"

#include "vtb/linalg/lanes.hh"
#include "vtb/linalg/vector_clones.hh"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace vtb::detail {

double approx_inverse_cbrt(double x) {
  if (!(x > 1e-200 && x < 1e200)) return std::cbrt(1 / x);
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits = 0x5540000000000000ull - bits / 3;
  double y;
  std::memcpy(&y, &bits, sizeof bits);
  for (int it = 0; it < 2; ++it) y = y * (4 - x * y * y * y) * (1.0 / 3.0);
  return y;
}

namespace {

using V = Lane<4>;
using M = LaneMask<4>;

/// c = a x b, each a column of three lanes.
[[gnu::always_inline]] inline void cross(const V* a, const V* b, V* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

} // namespace

VTB_VECTOR_CLONES void polar_rotations(int n, const double* A, double* R, unsigned char* ok) {
  for (int k0 = 0; k0 < n; k0 += 4) {
    const int lanes = n - k0 < 4 ? n - k0 : 4;
    // X's nine entries, lane l = matrix k0 + l (identity in the lanes past n: converged at once).
    V X[9], C[9], Rn[9];
    for (int e = 0; e < 9; ++e)
      for (int l = 0; l < 4; ++l) X[e][l] = l < lanes ? A[9 * (k0 + l) + e] : (e % 4 == 0 ? 1.0 : 0.0);
    M active = {-1, -1, -1, -1}, good = {-1, -1, -1, -1}, scaled = {-1, -1, -1, -1};
    for (int it = 0; it < 30; ++it) {
      cross(X + 3, X + 6, C);
      cross(X + 6, X, C + 3);
      cross(X, X + 3, C + 6);
      const V det = X[0] * C[0] + X[1] * C[1] + X[2] * C[2];
      const M fails = active & ~((det > 0) & (det < HUGE_VAL)); // NaN fails too
      good &= ~fails;
      active &= ~fails;
      V g = {1, 1, 1, 1};
      for (int l = 0; l < 4; ++l)
        if (scaled[l] && active[l]) g[l] = approx_inverse_cbrt(det[l]);
      const V inv = 1 / (g * det);
      V change = {0, 0, 0, 0};
      for (int e = 0; e < 9; ++e) {
        Rn[e] = 0.5 * (g * X[e] + C[e] * inv);
        const V step = Rn[e] - X[e];
        change += step * step;
      }
      const M done = active & (change < 1e-30);
      scaled = change > 1e-4;
      for (int e = 0; e < 9; ++e) X[e] = active ? Rn[e] : X[e]; // a converged lane keeps its R
      active &= ~done;
      if (!(active[0] | active[1] | active[2] | active[3])) break;
    }
    for (int l = 0; l < lanes; ++l) {
      ok[k0 + l] = good[l] && !active[l];
      for (int e = 0; e < 9; ++e) R[9 * (k0 + l) + e] = X[e][l];
    }
  }
}

} // namespace vtb::detail
