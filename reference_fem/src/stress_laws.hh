#pragma once
// Internal to reference_fem: the geometrically exact Kelvin-Voigt laws of `[solver] kinematics`,
// as the first Piola-Kirchhoff stress P of the deformation gradient F = I + grad u and the
// velocity gradient grad v, and its derivative along a displacement-gradient direction G:
//
//   "nonlinear" (St. Venant-Kirchhoff): P_e = F s(E),  E = (F^T F - I) / 2;
//   "neo-hookean" (compressible, Ogden/Simo's form W = mu/2 (tr C - d) - mu ln J + lambda/2 ln^2 J):
//       P_e = mu (F - F^-T) + lambda ln J F^-T;
//   both plus the rate term  P_v = F tau s(sym(F^T grad v)),  s(A) = lambda tr(A) I + 2 mu A,
//
// which are the linear Kelvin-Voigt law for small displacements (lambda the plane-stress one in
// 2D, where the neo-Hookean form is the plane-strain energy with that lambda: exact in the small-
// strain limit, a model of the thin sheet beyond it). The derivative ties v to u as in the
// Newton step, d(grad v) = rate G (rate = 1/dt for backward Euler, 0 statically):
//   dP_e(svk) = G s(E) + F s(sym(F^T G)),
//   dP_e(nh)  = mu G + (mu - lambda ln J) F^-T G^T F^-T + lambda tr(F^-1 G) F^-T,
//   dP_v      = G S_v + F tau s(sym(G^T grad v + rate F^T G)).
// A neo-Hookean F with J <= 0 (an inverted element) gives a NaN stress, which the Newton
// iteration reads as a failed step (and the static load stepping cuts its increment).

#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <cmath>
#include <limits>

namespace vtb::fem {

template <int dim> dealii::Tensor<2, dim> svk_stress(const dealii::Tensor<2, dim>& A, double lambda, double mu) {
  return lambda * dealii::trace(A) * dealii::unit_symmetric_tensor<dim>() + 2 * mu * A;
}

template <int dim> dealii::Tensor<2, dim> sym(const dealii::Tensor<2, dim>& A) {
  return 0.5 * (A + dealii::transpose(A));
}

/// The stress at one quadrature point and its derivative along any G, for one law.
template <int dim> class StressPoint {
public:
  StressPoint(const dealii::Tensor<2, dim>& F, const dealii::Tensor<2, dim>& grad_v, bool neo_hookean, double lambda,
              double mu, double tau, double rate)
      : m_F(F), m_grad_v(grad_v), m_neo_hookean(neo_hookean), m_lambda(lambda), m_mu(mu), m_tau(tau), m_rate(rate) {
    const dealii::Tensor<2, dim> I = dealii::unit_symmetric_tensor<dim>();
    const auto Ft = dealii::transpose(F);
    m_Sv = tau * svk_stress<dim>(sym<dim>(Ft * grad_v), lambda, mu);
    if (neo_hookean) {
      const double J = dealii::determinant(F);
      if (!(J > 0)) {
        m_P = std::numeric_limits<double>::quiet_NaN() * I;
        return;
      }
      m_log_J = std::log(J);
      m_F_inv = dealii::invert(F);
      m_F_inv_T = dealii::transpose(m_F_inv);
      m_P = mu * (F - m_F_inv_T) + lambda * m_log_J * m_F_inv_T + F * m_Sv;
    } else {
      m_Se = svk_stress<dim>(0.5 * (Ft * F - I), lambda, mu);
      m_P = F * (m_Se + m_Sv);
    }
  }

  const dealii::Tensor<2, dim>& P() const { return m_P; }
  const dealii::Tensor<2, dim>& F() const { return m_F; }

  /// dP along a displacement-gradient direction G (grad v moving by rate G).
  dealii::Tensor<2, dim> dP(const dealii::Tensor<2, dim>& G) const {
    const auto FtG = dealii::transpose(m_F) * G;
    const auto dSv = m_tau * svk_stress<dim>(sym<dim>(dealii::transpose(G) * m_grad_v + m_rate * FtG), m_lambda, m_mu);
    dealii::Tensor<2, dim> d = G * m_Sv + m_F * dSv;
    if (m_neo_hookean) {
      d += m_mu * G + (m_mu - m_lambda * m_log_J) * (m_F_inv_T * dealii::transpose(G) * m_F_inv_T) +
           m_lambda * dealii::trace(m_F_inv * G) * m_F_inv_T;
    } else {
      d += G * m_Se + m_F * svk_stress<dim>(sym<dim>(FtG), m_lambda, m_mu);
    }
    return d;
  }

private:
  dealii::Tensor<2, dim> m_F, m_grad_v, m_P, m_Se, m_Sv, m_F_inv, m_F_inv_T;
  bool m_neo_hookean;
  double m_lambda, m_mu, m_tau, m_rate, m_log_J = 0;
};

} // namespace vtb::fem
