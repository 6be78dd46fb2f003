#pragma once
// Internal to reference_fem: `[solver] kinematics = "nonlinear"`, the total-Lagrangian St.
// Venant-Kirchhoff solid with the Kelvin-Voigt rate term, so that large pokes are checked on the
// same (geometrically exact) physics as the springs:
//   F = I + grad u,  E = (F^T F - I) / 2,  Edot = sym(F^T grad v),
//   S = s(E + tau Edot),  s(A) = lambda tr(A) I + 2 mu A   (lambda the plane-stress one in 2D),
//   f_int,i = int (F S) : grad N_i dV   (times the thickness in 2D),
// which is the linear Kelvin-Voigt law for small displacements. The tangent is taken with
// respect to u with v tied to it as v = (u - u_old) * rate (rate = 1/dt for backward Euler, 0
// for a static solve): dP = G S + F s(sym(F^T G) + tau sym(G^T grad v + rate F^T G)) for each
// shape function's gradient G.

#include "grid.hh"

#include <deal.II/base/tensor.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/fe_values_extractors.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>

#include <vector>

namespace vtb::fem {

template <int dim> dealii::Tensor<2, dim> svk_stress(const dealii::Tensor<2, dim>& A, double lambda, double mu) {
  return lambda * dealii::trace(A) * dealii::unit_symmetric_tensor<dim>() + 2 * mu * A;
}

template <int dim> dealii::Tensor<2, dim> sym(const dealii::Tensor<2, dim>& A) {
  return 0.5 * (A + dealii::transpose(A));
}

/// What assemble_nonlinear adds: the internal force vector f_int(u, v) (no constraints: every
/// dof, for the reactions) and/or the tangent d f_int / du, with the constrained rows and
/// columns eliminated (a positive diagonal left, as A0 has).
template <int dim, class Vector, class Matrix> struct NonlinearTargets {
  Vector* force = nullptr;
  Matrix* tangent = nullptr;
  double rate = 0; ///< dv/du along the step: 1/dt (backward Euler) or 0 (static)
};

/// u and v must see every dof of the locally owned cells (ghosted vectors under MPI).
template <int dim, class GhostedVector, class Vector, class Matrix>
void assemble_nonlinear(const dealii::Mapping<dim>& mapping, const dealii::FESystem<dim>& fe,
                        const dealii::DoFHandler<dim>& dofs, const MaterialDesc& mat, int degree,
                        const GhostedVector& u, const GhostedVector& v,
                        const dealii::AffineConstraints<double>& constraints,
                        NonlinearTargets<dim, Vector, Matrix> out) {
  const auto [lambda, mu] = lame<dim>(mat);
  const double tau = mat.retardation_time, thickness = dim == 2 ? mat.thickness : 1.0;
  // Degree 2p integrates the tangent's polynomial parts; the stress is of higher degree in u,
  // so one more point order keeps the quadrature error below the discretisation's.
  const dealii::QGaussSimplex<dim> quad(static_cast<unsigned int>(degree + 2));
  dealii::FEValues<dim> fev(mapping, fe, quad, dealii::update_gradients | dealii::update_JxW_values);
  const dealii::FEValuesExtractors::Vector disp(0);
  const unsigned int nd = fe.n_dofs_per_cell();
  dealii::FullMatrix<double> k(nd, nd);
  dealii::Vector<double> r(nd);
  std::vector<dealii::Tensor<2, dim>> grad_u(quad.size()), grad_v(quad.size());
  std::vector<dealii::types::global_dof_index> local(nd);
  std::vector<unsigned int> comp(nd);
  for (unsigned int i = 0; i < nd; ++i) comp[i] = fe.system_to_component_index(i).first;
  const dealii::AffineConstraints<double> none;
  for (const auto& cell : dofs.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fev.reinit(cell);
    fev[disp].get_function_gradients(u, grad_u);
    fev[disp].get_function_gradients(v, grad_v);
    k = 0;
    r = 0;
    for (unsigned int q = 0; q < quad.size(); ++q) {
      const double jxw = fev.JxW(q) * thickness;
      const dealii::Tensor<2, dim> F = dealii::unit_symmetric_tensor<dim>() + grad_u[q];
      const dealii::Tensor<2, dim> E = 0.5 * (dealii::transpose(F) * F - dealii::unit_symmetric_tensor<dim>());
      const dealii::Tensor<2, dim> S =
          svk_stress<dim>(E + tau * sym<dim>(dealii::transpose(F) * grad_v[q]), lambda, mu);
      const dealii::Tensor<2, dim> P = F * S;
      for (unsigned int i = 0; i < nd; ++i) {
        const dealii::Tensor<1, dim> gi = fev.shape_grad(i, q);
        r[i] += (P * gi)[comp[i]] * jxw;
        if (!out.tangent) continue;
        for (unsigned int j = 0; j < nd; ++j) {
          dealii::Tensor<2, dim> G;
          G[comp[j]] = fev.shape_grad(j, q);
          const dealii::Tensor<2, dim> FtG = dealii::transpose(F) * G;
          const dealii::Tensor<2, dim> dS = svk_stress<dim>(
              sym<dim>(FtG) + tau * sym<dim>(dealii::transpose(G) * grad_v[q] + out.rate * FtG), lambda, mu);
          k(i, j) += ((G * S + F * dS) * gi)[comp[i]] * jxw;
        }
      }
    }
    cell->get_dof_indices(local);
    if (out.force) none.distribute_local_to_global(r, local, *out.force);
    if (out.tangent) constraints.distribute_local_to_global(k, local, *out.tangent);
  }
  if (out.force) out.force->compress(dealii::VectorOperation::add);
  if (out.tangent) out.tangent->compress(dealii::VectorOperation::add);
}

} // namespace vtb::fem
