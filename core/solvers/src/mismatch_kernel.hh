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
/// Each of n pairs (a, b), stored one after the other, scaled to unit length: (cos, sin) of
/// its angle, by newton_inverse_sqrt (no square root, no division: the loop vectorises where
/// a square root and a division per node waited on the divider, docs/performance.md). A pair
/// with a^2 + b^2 not within [kTiny, inf) (zero, denormal, not finite) is left as it is and
/// the function returns true: the caller's exact pass takes it.
bool unit_pairs(int n, double* ab);

/// The smallest a^2 + b^2 unit_pairs scales (its seed's exponent trick needs a normal number).
inline constexpr double kTinyPair = 1e-280;

void mismatch_sin2(int n, const double* p, const double* q, const double* w, const double* cx, const double* cy,
                   const double* trigger, double* s2, bool& outgrown, bool& rare);

} // namespace vtb::detail
