// Finite-difference checks of the Voigt element kernels (docs/testing.md: every force and
// Jacobian). Central differences have error O(h^2 |f'''|); with h = 1e-6 on O(1) data the
// truncation error is ~1e-12 and round-off ~eps/h ~ 1e-10, so 1e-7 relative is a safe bound.
#include "vtb/springs/spring_kernels.hh"

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <cmath>

namespace vtb {
namespace {

constexpr double kH = 1e-6;
constexpr double kTol = 1e-7;

double spring_energy(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj, double L0, double k) {
  const double l = (xj - xi).norm();
  return 0.5 * k * (l - L0) * (l - L0);
}

class KernelFd : public ::testing::TestWithParam<double> {}; // param: stretch ratio l / L0

TEST_P(KernelFd, ForceIsMinusEnergyGradient) {
  const double ratio = GetParam();
  const Eigen::Vector3d xi(0.1, -0.2, 0.3), dir = Eigen::Vector3d(0.6, 0.3, -0.74).normalized();
  const double L0 = 0.7, k = 3.0;
  const Eigen::Vector3d xj = xi + ratio * L0 * dir;
  const Eigen::Vector3d f = voigt_force<3>(xi, xj, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), L0, k, 0.0);
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[a] = kH;
    const double g = (spring_energy(xi + e, xj, L0, k) - spring_energy(xi - e, xj, L0, k)) / (2 * kH);
    EXPECT_NEAR(f[a], -g, kTol * k);
  }
}

TEST_P(KernelFd, JacobianMatchesForceDifferences) {
  const double ratio = GetParam();
  const Eigen::Vector3d xi(0.1, -0.2, 0.3), dir = Eigen::Vector3d(-0.2, 0.9, 0.4).normalized();
  const double L0 = 0.5, k = 2.0;
  const Eigen::Vector3d xj = xi + ratio * L0 * dir;
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d K = spring_jacobian<3>(xi, xj, L0, k, false);
  for (int b = 0; b < 3; ++b) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[b] = kH;
    const Eigen::Vector3d dfj =
        (voigt_force<3>(xi, xj + e, z, z, L0, k, 0) - voigt_force<3>(xi, xj - e, z, z, L0, k, 0)) / (2 * kH);
    const Eigen::Vector3d dfi =
        (voigt_force<3>(xi + e, xj, z, z, L0, k, 0) - voigt_force<3>(xi - e, xj, z, z, L0, k, 0)) / (2 * kH);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(K(a, b), dfj[a], kTol * k) << "d f_i / d x_j";
      EXPECT_NEAR(-K(a, b), dfi[a], kTol * k) << "d f_i / d x_i";
    }
  }
  EXPECT_TRUE(K.isApprox(K.transpose()));
}

/// The Voigt element with spring and dashpot together, in 2D and 3D: d f_i / d v_j is the
/// dashpot block (the force is linear in v, so the difference is exact but for round-off), and
/// at v = 0 d f_i / d x_j is the spring block even with c != 0. The element's direction turns
/// with the stretch parameter, so each case probes another n.
template <int dim> void check_voigt_element(double ratio) {
  Vec<dim> dir, xi, vi, vj;
  for (int a = 0; a < dim; ++a) {
    dir[a] = std::cos(3.0 * ratio + 1.7 * a);
    xi[a] = 0.1 * (a + 1);
    vi[a] = 0.2 * std::sin(1.0 + a);
    vj[a] = -0.3 * std::cos(2.0 * a);
  }
  dir.normalize();
  const double L0 = 0.4, k = 2.5, c = 1.5;
  const Vec<dim> xj = xi + ratio * L0 * dir, z = Vec<dim>::Zero();
  const Mat<dim> C = dashpot_jacobian<dim>(xi, xj, c), K = spring_jacobian<dim>(xi, xj, L0, k, false);
  for (int b = 0; b < dim; ++b) {
    Vec<dim> e = Vec<dim>::Zero();
    e[b] = kH;
    const Vec<dim> dv =
        (voigt_force<dim>(xi, xj, vi, vj + e, L0, k, c) - voigt_force<dim>(xi, xj, vi, vj - e, L0, k, c)) / (2 * kH);
    const Vec<dim> dx =
        (voigt_force<dim>(xi, xj + e, z, z, L0, k, c) - voigt_force<dim>(xi, xj - e, z, z, L0, k, c)) / (2 * kH);
    for (int a = 0; a < dim; ++a) {
      EXPECT_NEAR(C(a, b), dv[a], kTol * c) << "d f_i / d v_j, dim " << dim;
      EXPECT_NEAR(K(a, b), dx[a], kTol * k) << "d f_i / d x_j with the dashpot present, dim " << dim;
    }
  }
  // The dashpot acts along the element: a relative velocity across it does nothing.
  Vec<dim> across = Vec<dim>::Zero();
  across[0] = -dir[1];
  across[1] = dir[0];
  EXPECT_LT((C * across).norm(), 1e-14 * c);
}

TEST_P(KernelFd, VoigtElementJacobiansMatchDifferences2D) {
  check_voigt_element<2>(GetParam());
}
TEST_P(KernelFd, VoigtElementJacobiansMatchDifferences3D) {
  check_voigt_element<3>(GetParam());
}

INSTANTIATE_TEST_SUITE_P(StretchedAndCompressed, KernelFd, ::testing::Values(0.6, 1.0, 1.3));

TEST(Kernels, ClampedJacobianIsPositiveSemidefiniteUnderCompression) {
  const Eigen::Vector2d xi(0, 0), xj(0.5, 0);
  const Eigen::Matrix2d K = spring_jacobian<2>(xi, xj, 1.0, 1.0, true);
  EXPECT_GE(K.selfadjointView<Eigen::Lower>().eigenvalues().minCoeff(), 0.0);
  const Eigen::Matrix2d Ku = spring_jacobian<2>(xi, xj, 1.0, 1.0, false);
  EXPECT_LT(Ku.selfadjointView<Eigen::Lower>().eigenvalues().minCoeff(), 0.0) << "the unclamped term is indefinite";
}

TEST(Kernels, DashpotCarriesNoTorqueAndIgnoresRigidRotation) {
  // Relative velocity of a rigid rotation is perpendicular to the element: no dashpot force.
  const Eigen::Vector2d xi(0.1, 0.2), xj(0.5, -0.1);
  const double w = 3.0;
  auto rot = [w](const Eigen::Vector2d& x) { return Eigen::Vector2d(-w * x.y(), w * x.x()); };
  const Eigen::Vector2d f = voigt_force<2>(xi, xj, rot(xi), rot(xj), (xj - xi).norm(), 10.0, 4.0);
  EXPECT_LT(f.norm(), 1e-14);
}

} // namespace
} // namespace vtb
