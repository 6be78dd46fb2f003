// The 2D tensor filter's mismatch kernel (core/solvers/src/filtered/mismatch_kernel.cc: four springs per
// vector, the ends' rotations gathered, the largest sin^2 kept as a fraction) against the
// definition spring by spring, on every remainder of the spring count by the vector's width.
#include "../../core/solvers/src/filtered/mismatch_kernel.hh"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace vtb {
namespace {

/// Springs laid out as the kernel reads them, on `nodes` nodes with unit (cos, sin) each.
struct Springs {
  std::vector<double> p, q, trigger, turn;
  std::vector<std::array<int, 2>> edge;

  Springs(int n, int nodes, std::mt19937& rng) {
    std::uniform_real_distribution<double> angle(-0.3, 0.3), len(0.5, 2.0), tr(1e-4, 2e-2);
    std::uniform_int_distribution<int> pick(0, nodes - 1);
    for (int i = 0; i < nodes; ++i) {
      const double a = angle(rng);
      turn.push_back(std::cos(a));
      turn.push_back(std::sin(a));
    }
    for (int s = 0; s < n; ++s) {
      // (p, q) = |d| |D| (cos, sin) of the angle from D to d.
      const double a = angle(rng), l = len(rng);
      p.push_back(l * std::cos(a));
      q.push_back(l * std::sin(a));
      trigger.push_back(tr(rng));
      edge.push_back({pick(rng), pick(rng)});
    }
  }

  /// Spring s's sin^2 by its definition, d . t and |d x t| from t = (R_i + R_j) D.
  double sin2(int s, double& dot) const {
    const auto [i, j] = edge[static_cast<std::size_t>(s)];
    const double cx = turn[2 * i] + turn[2 * j], cy = turn[2 * i + 1] + turn[2 * j + 1];
    const auto k = static_cast<std::size_t>(s);
    dot = cx * p[k] + cy * q[k];
    const double cross = cy * p[k] - cx * q[k];
    return cross * cross / ((p[k] * p[k] + q[k] * q[k]) * (cx * cx + cy * cy));
  }

  double largest(bool& outgrown, bool& rare) const {
    return detail::largest_sin2(static_cast<int>(p.size()), p.data(), q.data(), edge.data(), turn.data(),
                                trigger.data(), outgrown, rare);
  }
};

TEST(MismatchKernel, FindsTheLargestSin2AndTheOutgrownSpringOnEveryRemainder) {
  // The kernel divides once, for the largest fraction; the definition divides per spring. Both
  // give the same quotient of the same two products: equal within 4 ulp (EXPECT_DOUBLE_EQ).
  std::mt19937 rng(11);
  for (int n = 0; n <= 13; ++n) {
    Springs sp(n, 9, rng);
    double expected = 0;
    bool any_over = false;
    for (int s = 0; s < n; ++s) {
      double dot;
      const double s2 = sp.sin2(s, dot);
      ASSERT_GT(dot, 0.0); // angles below 0.9 rad: no rare spring
      expected = std::max(expected, s2);
      any_over |= s2 > sp.trigger[static_cast<std::size_t>(s)];
    }
    bool outgrown = true, rare = true;
    EXPECT_DOUBLE_EQ(sp.largest(outgrown, rare), expected) << n << " springs";
    EXPECT_EQ(outgrown, any_over) << n << " springs";
    EXPECT_FALSE(rare) << n << " springs";
    if (n == 0) continue;
    // Each spring in turn (the last ones sit in the padded vector) made the only one past
    // its trigger, then the only one past 90 degrees.
    for (int s = 0; s < n; ++s) {
      Springs one = sp;
      std::fill(one.trigger.begin(), one.trigger.end(), 10.0); // sin^2 <= 1: none passes
      double dot;
      one.trigger[static_cast<std::size_t>(s)] = 0.5 * one.sin2(s, dot);
      EXPECT_TRUE((one.largest(outgrown, rare), outgrown)) << "spring " << s << " of " << n;
      one.trigger[static_cast<std::size_t>(s)] = 10.0;
      EXPECT_FALSE((one.largest(outgrown, rare), outgrown)) << "spring " << s << " of " << n;
      one.p[static_cast<std::size_t>(s)] *= -1; // d . t < 0
      one.q[static_cast<std::size_t>(s)] *= -1;
      one.largest(outgrown, rare);
      EXPECT_TRUE(rare) << "spring " << s << " of " << n;
      one.p[static_cast<std::size_t>(s)] = std::numeric_limits<double>::quiet_NaN();
      one.largest(outgrown, rare);
      EXPECT_TRUE(rare) << "spring " << s << " of " << n << " (NaN)";
    }
  }
}

} // namespace
} // namespace vtb
