#include "mismatch_kernel.hh"

#include "vtb/linalg/lanes.hh"
#include "vtb/linalg/vector_clones.hh"
#include "vtb/springs/spring_kernels.hh"

#include <array>
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

namespace {

using Doubles = Lane<4>;
using Mask = LaneMask<4>;

/// Four springs' lanes from four consecutive values.
[[gnu::always_inline]] inline Doubles lanes(const double* x) {
  return load<4>(x);
}

/// Per lane the largest sin^2 so far as a fraction num / den (compared by cross products: no
/// division per spring, the divider bounded this loop), and whether a spring outgrew its
/// trigger or was not ok (see largest_sin2).
struct LargestSin2 {
  Doubles num = {0, 0, 0, 0}, den = {1, 1, 1, 1};
  Mask out = {0, 0, 0, 0}, odd = {0, 0, 0, 0};
};

/// Adds four springs' lanes (`lane`: which of them are springs).
[[gnu::always_inline]] inline void add_lanes(LargestSin2& b, Doubles P, Doubles Q, Doubles X, Doubles Y, Doubles T,
                                             Mask lane) {
  const double inf = std::numeric_limits<double>::infinity();
  const Doubles cross = Y * P - X * Q, dot = X * P + Y * Q;
  const Doubles d = (P * P + Q * Q) * (X * X + Y * Y), c2 = cross * cross; // |d|^2 |D|^2 |c|^2
  const Mask ok = (dot > 0) & (d > 0) & (d < inf);                         // false for NaN
  const Doubles nu = ok ? c2 : 0.0, de = ok ? d : 1.0;
  const Mask bigger = nu * b.den > b.num * de;
  b.num = bigger ? nu : b.num;
  b.den = bigger ? de : b.den;
  b.out |= (c2 > T * d) & lane;
  b.odd |= ~ok & lane;
}

/// Four springs' ends' (cos, sin) summed, as the lanes (cx...) and (cy...).
[[gnu::always_inline]] inline void gather_ends(const std::array<int, 2>* e, const double* turn, Doubles& X,
                                               Doubles& Y) {
  const Lane<2> c0 = load<2>(turn + 2 * e[0][0]) + load<2>(turn + 2 * e[0][1]);
  const Lane<2> c1 = load<2>(turn + 2 * e[1][0]) + load<2>(turn + 2 * e[1][1]);
  const Lane<2> c2 = load<2>(turn + 2 * e[2][0]) + load<2>(turn + 2 * e[2][1]);
  const Lane<2> c3 = load<2>(turn + 2 * e[3][0]) + load<2>(turn + 2 * e[3][1]);
  X = Doubles{c0[0], c1[0], c2[0], c3[0]};
  Y = Doubles{c0[1], c1[1], c2[1], c3[1]};
}

} // namespace

VTB_VECTOR_CLONES double largest_sin2(int n, const double* p, const double* q, const std::array<int, 2>* edge,
                                      const double* turn, const double* trigger, bool& outgrown, bool& rare) {
  LargestSin2 b;
  int s = 0;
  for (; s + 4 <= n; s += 4) {
    Doubles X, Y;
    gather_ends(edge + s, turn, X, Y);
    add_lanes(b, lanes(p + s), lanes(q + s), X, Y, lanes(trigger + s), Mask{-1, -1, -1, -1});
  }
  if (s < n) { // the last springs, in lanes padded with zeros (p = q = 0: not ok, masked out)
    double pad[5][4] = {};
    for (int k = 0; s + k < n; ++k) {
      const auto [i, j] = edge[s + k];
      pad[0][k] = p[s + k];
      pad[1][k] = q[s + k];
      pad[2][k] = turn[2 * i] + turn[2 * j];
      pad[3][k] = turn[2 * i + 1] + turn[2 * j + 1];
      pad[4][k] = trigger[s + k];
    }
    const Mask lane = {0 < n - s ? -1 : 0, 1 < n - s ? -1 : 0, 2 < n - s ? -1 : 0, 3 < n - s ? -1 : 0};
    add_lanes(b, lanes(pad[0]), lanes(pad[1]), lanes(pad[2]), lanes(pad[3]), lanes(pad[4]), lane);
  }
  long any_out = 0, any_odd = 0;
  double best_num = 0, best_den = 1;
  for (int k = 0; k < 4; ++k) {
    any_out |= b.out[k];
    any_odd |= b.odd[k];
    if (b.num[k] * best_den > best_num * b.den[k]) {
      best_num = b.num[k];
      best_den = b.den[k];
    }
  }
  outgrown = any_out != 0;
  rare = any_odd != 0;
  return best_num / best_den;
}

} // namespace vtb::detail
