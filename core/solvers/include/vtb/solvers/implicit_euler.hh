#pragma once
/// \file
/// Linearised backward Euler with the true spring Jacobian (Baraff and Witkin 1998):
///   (M (1 + dt gamma) - dt C_J - dt^2 K_J) dv = dt (f(u, v) + f_ext(t + dt) + dt K_J v),
///   v += dv,  u += dt v,
/// with K_J = df/dx (compressed springs' transverse term clamped at zero so the matrix stays
/// SPD) and C_J = df/dv of the dashpots. A sparse LDL^T is refactorised every step on a
/// pattern ordered once (AMD), so the step allocates nothing. The honest "what the filter
/// approximates".

#include "vtb/linalg/ordered_ldlt.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/integrator.hh"

namespace vtb {

template <int dim> class ImplicitEuler final : public Integrator<dim> {
public:
  ImplicitEuler(const Model<dim>& model, double dt);
  void step(State<dim>& s) override;
  std::string_view name() const override { return solvers::kImplicitEuler; }

private:
  const Model<dim>& m_model;
  OrderedLDLT m_solver;
  /// Per spring and block entry (p, q): value offsets of blocks ii, jj, ij, or -1 where the
  /// node is constrained or the entry lies in the other triangle.
  std::vector<std::array<int, 3>> m_slot;
  std::vector<int> m_cell_slot; ///< per cell, block (a <= b) and entry: the value's slot, -1 if not stored
  std::vector<int> m_diag_slot; ///< per free dof
  Nodal<dim> m_force;
  Eigen::MatrixXd m_rhs; ///< ordered, one column
};

} // namespace vtb
