#pragma once
// The 2D tensor filter's per-spring direction mismatch, as one vector loop (tensor_filter.cc's
// scan; docs/performance.md item 12).

#include <array>

namespace vtb::detail {

/// Each of n pairs (a, b), stored one after the other, made the (cos, sin) of its angle: in one
/// vector loop by newton_inverse_sqrt (no square root, no division: a square root and a
/// division per node waited on the divider, docs/performance.md), then, for the rare pair whose
/// a^2 + b^2 is not a normal finite number (its seed's exponent trick needs one), exactly: a
/// denormal pair by a square root and a division, a zero or non-finite one as (1, 0) (a
/// non-finite state: the run's watch stops it).
void unit_pairs(int n, double* ab);

/// Over springs laid out column by column: p = d . D and q = D x d (so p^2 + q^2 = |d|^2
/// |D|^2, no third array), with the ends' summed (cos, sin) c = (cx, cy) gathered from `turn`
/// (2 x nodes) by `edge` (the springs' node pairs), so that with t = (R_i + R_j) D: d . t = cx
/// p + cy q, d x t = cy p - cx q and |d|^2 |t|^2 = (p^2 + q^2) |c|^2. Returns the largest sin^2
/// of the angle between d and t over the springs with d . t > 0 and |d| |t| positive and
/// finite (0 if none); sets `rare` when a spring is not one of them (the caller's exact pass
/// then takes them all), and `outgrown` when a spring's sin^2 passes its trigger. Four springs
/// per vector, no branch and no division but one; the ends' sums are made here rather than
/// stored by a pass of their own (the passes' per-spring arrays did not fit L1,
/// docs/performance.md item 15).
double largest_sin2(int n, const double* p, const double* q, const std::array<int, 2>* edge, const double* turn,
                    const double* trigger, bool& outgrown, bool& rare);

/// The same in 3D from each spring's d = rest + u_j - u_i (`rest`, `ref`: 3 values per spring,
/// `u`: 3 per node) and t = (R_i + R_j) D (`rotation`: 9 per node, column-major; D from `ref`),
/// with the same `outgrown` and `rare` (the caller's exact pass then takes them all): a gather
/// per chunk of springs, then four springs per vector.
double largest_sin2_3d(int n, const std::array<int, 2>* edge, const double* rest, const double* ref, const double* u,
                       const double* rotation, const double* trigger, bool& outgrown, bool& rare);

} // namespace vtb::detail
