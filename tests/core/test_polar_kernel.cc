// The 3D tensor filter's polar kernel (core/solvers/src/filtered/polar_kernel.cc: four matrices per
// vector, each lane iterating until all four have converged) against the SVD's U V^T, with
// matrices that fail (det <= 0, NaN) among those that converge, on every remainder of the
// count by the vector's width.
#include "../../core/solvers/src/filtered/polar_kernel.hh"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace vtb {
namespace {

using Mat3 = Eigen::Matrix3d;

TEST(PolarKernel, GivesTheSvdsRotationAndFlagsTheMatricesItCannotTake) {
  // Matrices R (I + E) with E random up to 0.3: singular values 0.5-1.6, as the rotations'
  // scaled neighbourhoods. The iteration stops at round-off: 1e-12 against the SVD (|R| =
  // sqrt 3).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int n = 1; n <= 11; ++n) {
    std::vector<double> A(9 * static_cast<std::size_t>(n)), R(A.size());
    std::vector<unsigned char> ok(static_cast<std::size_t>(n), 7);
    for (int k = 0; k < n; ++k) {
      const Mat3 rot = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
      Mat3 E;
      for (int e = 0; e < 9; ++e) E.data()[e] = 0.3 * unit(rng);
      Mat3 a = rot * (Mat3::Identity() + E);
      if (k % 5 == 3) a.col(0) *= -1;                                     // det < 0
      if (k % 7 == 5) a(1, 1) = std::numeric_limits<double>::quiet_NaN(); // not finite
      std::copy_n(a.data(), 9, &A[9 * static_cast<std::size_t>(k)]);
    }
    detail::polar_rotations(n, A.data(), R.data(), ok.data());
    for (int k = 0; k < n; ++k) {
      const Mat3 a = Eigen::Map<const Mat3>(&A[9 * static_cast<std::size_t>(k)]);
      const bool fails = !a.allFinite() || a.determinant() <= 0;
      EXPECT_EQ(ok[static_cast<std::size_t>(k)], fails ? 0 : 1) << "matrix " << k << " of " << n;
      if (fails) continue;
      const Eigen::JacobiSVD<Mat3> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Mat3 expected = svd.matrixU() * svd.matrixV().transpose();
      EXPECT_LT((Eigen::Map<const Mat3>(&R[9 * static_cast<std::size_t>(k)]) - expected).norm(), 1e-12)
          << "matrix " << k << " of " << n;
    }
  }
}

TEST(PolarKernel, ApproximateInverseCubeRootIsWithinItsBound) {
  // Two Newton steps from the exponent's seed (whose error, up to 8 %, each step about squares:
  // 3.9e-4 at worst over a fine sweep of one period of the seed, three binades): within the
  // documented 4e-4 over the normal range, and libm's cbrt outside 1e-200 .. 1e200.
  for (double x = 1e-150; x < 1e150; x *= 1.37) {
    const double y = detail::approx_inverse_cbrt(x);
    EXPECT_LT(std::abs(y * std::cbrt(x) - 1), 4e-4) << x;
  }
  EXPECT_DOUBLE_EQ(detail::approx_inverse_cbrt(1e-250), std::cbrt(1e250));
}

} // namespace
} // namespace vtb
