#pragma once
// The 2D tensor filter's per-spring direction mismatch, as one vector loop (warped_filter.cc's
// scan; docs/performance.md item 12).

namespace vtb::detail {

/// Over springs laid out column by column: p = d . D, q = D x d, w = |d|^2 |D|^2 and the ends'
/// summed (cos, sin) c = (cx, cy), so that with t = (R_i + R_j) D: d . t = cx p + cy q,
/// d x t = cy p - cx q and |d|^2 |t|^2 = w |c|^2. Writes each spring's sin^2 of the angle
/// between d and t into s2 (0 where d . t <= 0, |d| |t| = 0 or not finite: `rare` is then set,
/// and the caller's exact pass takes them) and sets `outgrown` when a spring's sin^2 passes its
/// trigger. No gather and no branch: the loop vectorises.
/// Each of n pairs (a, b), stored one after the other, made the (cos, sin) of its angle: in one
/// vector loop by newton_inverse_sqrt (no square root, no division: a square root and a
/// division per node waited on the divider, docs/performance.md), then, for the rare pair whose
/// a^2 + b^2 is not a normal finite number (its seed's exponent trick needs one), exactly: a
/// denormal pair by a square root and a division, a zero or non-finite one as (1, 0) (a
/// non-finite state: the run's watch stops it).
void unit_pairs(int n, double* ab);

void mismatch_sin2(int n, const double* p, const double* q, const double* w, const double* cx, const double* cy,
                   const double* trigger, double* s2, bool& outgrown, bool& rare);

} // namespace vtb::detail
