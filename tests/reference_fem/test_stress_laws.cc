// The geometrically exact laws of the deal.II reference (reference_fem/src/stress_laws.hh) at one
// material point: their stress at small strain is the linear law's, and their derivative (the
// Newton tangent's integrand) is the stress's derivative, checked against central differences.
#include "stress_laws.hh"

#include <gtest/gtest.h>

#include <random>

namespace vtb::fem {
namespace {

template <int dim> dealii::Tensor<2, dim> random_tensor(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  dealii::Tensor<2, dim> A;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) A[i][j] = u(rng);
  return A;
}

template <int dim> void derivative_matches_differences(bool neo_hookean) {
  // Deformations with strains up to ~40 % and a rotation part, a velocity gradient, the step's
  // rate 1/dt: the central difference's error is O(h^2 |P'''|), about 1e-10 relative at h =
  // 1e-5 for these O(1) gradients, and its round-off 1e-16 / 1e-5; 1e-7 holds both with margin
  // and fails any wrong term of the derivative (each is O(1) here).
  std::mt19937 rng(7);
  const double lambda = 2.3, mu = 0.7, tau = 0.05, rate = 50;
  for (int trial = 0; trial < 20; ++trial) {
    const auto F = dealii::unit_symmetric_tensor<dim>() + random_tensor<dim>(rng, 0.4);
    const auto Lv = random_tensor<dim>(rng, 1.0), G = random_tensor<dim>(rng, 1.0);
    ASSERT_GT(dealii::determinant(F), 0.1);
    const double h = 1e-5;
    const StressPoint<dim> at(F, Lv, neo_hookean, lambda, mu, tau, rate);
    const StressPoint<dim> plus(F + h * G, Lv + rate * h * G, neo_hookean, lambda, mu, tau, rate);
    const StressPoint<dim> minus(F - h * G, Lv - rate * h * G, neo_hookean, lambda, mu, tau, rate);
    const auto fd = (plus.P() - minus.P()) / (2 * h), exact = at.dP(G);
    EXPECT_LT((fd - exact).norm(), 1e-7 * exact.norm()) << "dim " << dim << " trial " << trial;
  }
}

TEST(StressLaws, NeoHookeanDerivativeIsTheStressDerivative) {
  derivative_matches_differences<2>(true);
  derivative_matches_differences<3>(true);
}

TEST(StressLaws, SvkDerivativeIsTheStressDerivative) {
  derivative_matches_differences<2>(false);
  derivative_matches_differences<3>(false);
}

TEST(StressLaws, BothAreTheLinearKelvinVoigtLawAtSmallStrain) {
  // P = s(eps + tau eps_dot) + O(|grad u|^2): at gradients of 1e-6 the difference is ~1e-12,
  // relative 1e-6 of the stress; checked to 1e-5 relative.
  std::mt19937 rng(3);
  const double lambda = 1.5, mu = 0.4, tau = 0.1;
  const auto H = random_tensor<3>(rng, 1e-6), Lv = random_tensor<3>(rng, 1e-6);
  const auto linear = svk_stress<3>(sym<3>(H) + tau * sym<3>(Lv), lambda, mu);
  for (const bool nh : {false, true}) {
    const StressPoint<3> sp(dealii::unit_symmetric_tensor<3>() + H, Lv, nh, lambda, mu, tau, 0);
    EXPECT_LT((sp.P() - linear).norm(), 1e-5 * linear.norm()) << (nh ? "neo-hookean" : "svk");
  }
}

TEST(StressLaws, AnInvertedNeoHookeanPointHasNoFiniteStress) {
  // J <= 0 has no neo-Hookean energy: the Newton step must see a NaN and cut its increment.
  auto F = dealii::unit_symmetric_tensor<3>();
  F[0][0] = -0.2;
  EXPECT_TRUE(std::isnan(StressPoint<3>(F, {}, true, 1, 1, 0, 0).P().norm()));
}

} // namespace
} // namespace vtb::fem
