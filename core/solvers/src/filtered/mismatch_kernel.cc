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

/// Adds four pairs' d . t, |d x t|^2 and |d|^2 |t|^2 (`lane`: which of them are springs).
[[gnu::always_inline]] inline void add_terms(LargestSin2& b, Doubles dot, Doubles c2, Doubles d, Doubles T, Mask lane) {
  const double inf = std::numeric_limits<double>::infinity();
  const Mask ok = (dot > 0) & (d > 0) & (d < inf); // false for NaN
  const Doubles nu = ok ? c2 : 0.0, de = ok ? d : 1.0;
  const Mask bigger = nu * b.den > b.num * de;
  b.num = bigger ? nu : b.num;
  b.den = bigger ? de : b.den;
  b.out |= (c2 > T * d) & lane;
  b.odd |= ~ok & lane;
}

/// Adds four 2D springs' lanes from their (p, q) and ends' summed (cos, sin) (X, Y).
[[gnu::always_inline]] inline void add_lanes(LargestSin2& b, Doubles P, Doubles Q, Doubles X, Doubles Y, Doubles T,
                                             Mask lane) {
  const Doubles cross = Y * P - X * Q, dot = X * P + Y * Q;
  add_terms(b, dot, cross * cross, (P * P + Q * Q) * (X * X + Y * Y), T, lane); // |d|^2 |D|^2 |c|^2
}

/// The largest sin^2 over the four lanes and whether any lane outgrew or was odd.
double reduce(const LargestSin2& b, bool& outgrown, bool& rare) {
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
  return reduce(b, outgrown, rare);
}

VTB_VECTOR_CLONES double largest_sin2_3d(int n, const std::array<int, 2>* edge, const double* rest, const double* ref,
                                         const double* u, const double* rotation, const double* trigger, bool& outgrown,
                                         bool& rare) {
  // A chunk at a time: the gathers (d, and the ends' rotations summed times D) into lanes of
  // four springs, then the vector terms. Springs past n in the last chunk's lanes are zeros,
  // masked out.
  constexpr int kChunk = 128;
  alignas(32) double d[3][kChunk], t[3][kChunk], T[kChunk];
  LargestSin2 b;
  for (int s0 = 0; s0 < n; s0 += kChunk) {
    const int m = n - s0 < kChunk ? n - s0 : kChunk;
    for (int k = 0; k < m; ++k) {
      const int s = s0 + k, i = edge[s][0], j = edge[s][1];
      const double *Ri = rotation + 9 * i, *Rj = rotation + 9 * j, *D = ref + 3 * s;
      for (int p = 0; p < 3; ++p) {
        d[p][k] = rest[3 * s + p] + u[3 * j + p] - u[3 * i + p];
        // (R_i + R_j) D, the rotations column-major
        t[p][k] = (Ri[p] + Rj[p]) * D[0] + (Ri[3 + p] + Rj[3 + p]) * D[1] + (Ri[6 + p] + Rj[6 + p]) * D[2];
      }
      T[k] = trigger[s];
    }
    const int padded = (m + 3) & ~3;
    for (int k = m; k < padded; ++k) d[0][k] = d[1][k] = d[2][k] = t[0][k] = t[1][k] = t[2][k] = T[k] = 0;
    for (int k = 0; k < padded; k += 4) {
      const Doubles dx = lanes(d[0] + k), dy = lanes(d[1] + k), dz = lanes(d[2] + k);
      const Doubles tx = lanes(t[0] + k), ty = lanes(t[1] + k), tz = lanes(t[2] + k);
      const Doubles cx = dy * tz - dz * ty, cy = dz * tx - dx * tz, cz = dx * ty - dy * tx;
      const Doubles dd = (dx * dx + dy * dy + dz * dz) * (tx * tx + ty * ty + tz * tz);
      const Mask lane = {k < m ? -1 : 0, k + 1 < m ? -1 : 0, k + 2 < m ? -1 : 0, k + 3 < m ? -1 : 0};
      add_terms(b, dx * tx + dy * ty + dz * tz, cx * cx + cy * cy + cz * cz, dd, lanes(T + k), lane);
    }
  }
  return reduce(b, outgrown, rare);
}

} // namespace vtb::detail
