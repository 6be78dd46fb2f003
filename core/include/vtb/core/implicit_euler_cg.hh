#pragma once
/// \file
/// The linearised backward-Euler step of implicit_euler.hh solved by preconditioned conjugate
/// gradients instead of a sparse factor: what a practitioner writes for large meshes (Baraff
/// and Witkin 1998 used CG). The system A dv = b, A = M (1 + dt gamma) + sum over springs of
/// B_s = dt^2 K_s + dt D_s (the shared Jacobian assembly, compressed springs clamped so A is
/// SPD), is applied spring by spring without assembling a matrix; the preconditioner is A's
/// dim x dim diagonal blocks (block Jacobi); the iteration starts from the previous step's dv
/// (warm start) and stops when |r| <= cg_tolerance |b| (default 1e-8: the direct solve's
/// answer to that relative accuracy). Allocates nothing per step.

#include "vtb/core/integrator.hh"
#include "vtb/core/solver_names.hh"

#include <vector>

namespace vtb {

template <int dim> class ImplicitEulerCG final : public Integrator<dim> {
public:
  ImplicitEulerCG(const Model<dim>& model, double dt, double tolerance);
  void step(State<dim>& s) override;
  std::string_view name() const override { return solvers::kImplicitEuler; }
  /// Iterations of the last step's solve (for the benchmarks and the docs).
  int last_iterations() const { return m_iterations; }

private:
  void assemble(const State<dim>& s);
  void apply(const Nodal<dim>& x, Nodal<dim>& y) const; ///< y = A x on free nodes, 0 on constrained
  void precondition(const Nodal<dim>& r, Nodal<dim>& z) const;
  bool solve();

  const Model<dim>& m_model;
  double m_tolerance;
  int m_iterations = 0;
  Eigen::VectorXd m_mass;                            ///< m (1 + dt gamma), 0 on constrained nodes
  std::vector<Mat<dim>> m_block;                     ///< per spring: B_s
  std::vector<Mat<dim>> m_inv_diag;                  ///< per node: inverse of A's diagonal block (0 if constrained)
  Nodal<dim> m_force, m_b, m_x, m_r, m_z, m_p, m_ap; ///< per node
};

} // namespace vtb
