#pragma once
/// \file
/// Symplectic (semi-implicit) Euler: the baseline that the Courant limit breaks.
///   v+ = v + dt M^-1 (f(u, v) + f_ext(t)),   u+ = u + dt v+.

#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/integrator.hh"

namespace vtb {

template <int dim> class ExplicitEuler final : public Integrator<dim> {
public:
  ExplicitEuler(const Model<dim>& model, double dt);
  void step(State<dim>& s) override;
  std::string_view name() const override { return solvers::kExplicit; }

private:
  const Model<dim>& m_model;
  Nodal<dim> m_force, m_ext;
};

/// Largest eigenvalue omega^2 of M^-1 K on the free nodes, K the stiffness at rest.
/// `exact` uses a dense symmetric eigensolver (small meshes); otherwise 400 power iterations
/// with the operator applied spring by spring, nothing assembled (a lower bound, within 1 % on
/// the tested meshes; springs * dim^2 doubles of memory).
template <int dim> double max_omega_squared(const Model<dim>& model, bool exact);

/// Stability limit of symplectic Euler for a mode with omega^2 = w2 and Voigt damping
/// rate tau w2 + gamma: the step where dt^2 w2 + 2 (gamma + tau w2) dt = 4.
double explicit_critical_dt(double w2, double tau, double gamma);

} // namespace vtb
