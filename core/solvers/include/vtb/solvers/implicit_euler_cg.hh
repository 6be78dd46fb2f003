#pragma once
/// \file
/// The linearised backward-Euler step of implicit_euler.hh solved by preconditioned conjugate
/// gradients instead of a sparse factor: what a practitioner writes for large meshes (Baraff
/// and Witkin 1998 used CG). The system A dv = b, A = M (1 + dt gamma) + sum over springs of
/// B_s = dt^2 K_s + dt D_s (the shared Jacobian assembly, compressed springs clamped so A is
/// SPD), is applied spring by spring without assembling a matrix; the preconditioner is A's
/// dim x dim diagonal blocks (block Jacobi); the iteration starts from the last two steps' dv
/// extrapolated linearly (warm start) and stops when |r| <= cg_tolerance |b| (default 1e-8: the direct solve's
/// answer to that relative accuracy). Allocates nothing per step.
///
/// With `multigrid` the preconditioner is instead one symmetric V-cycle (multigrid.hh) of the
/// isotropic part of A, the full filter's H = M (1 + dt gamma) + dt C_L + dt^2 K_L, applied to
/// each coordinate: SPD, so CG stays CG, and it carries the long-range coupling block Jacobi
/// lacks (the Voigt term dt C dominates M at haptic steps; docs/performance.md).

#include "vtb/linalg/multigrid.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/integrator.hh"

#include <memory>
#include <vector>

namespace vtb {

template <int dim> class ImplicitEulerCG final : public Integrator<dim> {
public:
  ImplicitEulerCG(const Model<dim>& model, double dt, double tolerance, bool multigrid = false);
  void step(State<dim>& s) override;
  std::string_view name() const override { return solvers::kImplicitEuler; }
  /// Iterations of the last step's solve (for the benchmarks and the docs).
  int last_iterations() const { return m_iterations; }

private:
  void assemble(const State<dim>& s);
  void apply(const Nodal<dim>& x, Nodal<dim>& y) const; ///< y = A x on free nodes, 0 on constrained
  void precondition(const Nodal<dim>& r, Nodal<dim>& z);
  bool solve();

  const Model<dim>& m_model;
  double m_tolerance;
  int m_iterations = 0;
  Eigen::VectorXd m_mass;                            ///< m (1 + dt gamma), 0 on constrained nodes
  Eigen::VectorXd m_diag;                            ///< this step's diagonal: m_mass plus the couplings' dt^2 k + dt c
  std::vector<Mat<dim>> m_block;                     ///< per spring: B_s
  std::vector<Mat<dim>> m_cell_block;                ///< per cell and node pair (a, b): the volume term's block
  std::vector<Mat<dim>> m_inv_diag;                  ///< per node: inverse of A's diagonal block (0 if constrained)
  Nodal<dim> m_force, m_b, m_x, m_r, m_z, m_p, m_ap; ///< per node
  Nodal<dim> m_prev, m_prev2;                        ///< the dv of the two steps before the last
  std::unique_ptr<SymmetricMultigrid<dim>> m_mg;     ///< multigrid: the preconditioner
  Nodal<dim> m_free_r, m_free_z;                     ///< multigrid: r and z on the free nodes
};

} // namespace vtb
