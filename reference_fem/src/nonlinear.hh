#pragma once
// Internal to reference_fem: the geometrically exact Kelvin-Voigt solid of `[solver] kinematics =
// "nonlinear"` (St. Venant-Kirchhoff) and `"neo-hookean"`, total Lagrangian, so that large pokes
// are checked on geometrically exact physics as the springs are. Per quadrature point the law's
// first Piola-Kirchhoff stress P(F, grad v) and its derivative (stress_laws.hh);
//   f_int,i = int P : grad N_i dV   (times the thickness in 2D),
// and the tangent d f_int / du with v tied to u as v = (u - u_old) * rate (rate = 1/dt for
// backward Euler, 0 for a static solve).

#include "grid.hh"
#include "stress_laws.hh"

#include <deal.II/base/tensor.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/fe_values_extractors.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace vtb::fem {

/// What assemble_nonlinear adds: the internal force vector f_int(u, v) (no constraints: every
/// dof, for the reactions) and/or the tangent d f_int / du, with the constrained rows and
/// columns eliminated (a positive diagonal left, as A0 has).
template <int dim, class Vector, class Matrix> struct NonlinearTargets {
  Vector* force = nullptr;
  Matrix* tangent = nullptr;
  double rate = 0;          ///< dv/du along the step: 1/dt (backward Euler) or 0 (static)
  bool neo_hookean = false; ///< the law (stress_laws.hh): neo-Hookean, else St. Venant-Kirchhoff
  double* min_J = nullptr;  ///< if set: lowered to the smallest det F over the quadrature points (owned cells)
};

/// The smallest det F = det(I + grad u) over the quadrature points of the locally owned cells (the
/// points assemble_nonlinear evaluates the law at): a pass of gradients alone, so that a Newton
/// correction that would invert a cell is cut back before the tangent is assembled at it. u must
/// see every dof of the owned cells.
template <int dim, class GhostedVector>
double smallest_volume_ratio(const dealii::Mapping<dim>& mapping, const dealii::FESystem<dim>& fe,
                             const dealii::DoFHandler<dim>& dofs, int degree, const GhostedVector& u) {
  const dealii::QGaussSimplex<dim> quad(static_cast<unsigned int>(degree + 2));
  dealii::FEValues<dim> fev(mapping, fe, quad, dealii::update_gradients);
  const dealii::FEValuesExtractors::Vector disp(0);
  std::vector<dealii::Tensor<2, dim>> grad_u(quad.size());
  double smallest = std::numeric_limits<double>::infinity();
  for (const auto& cell : dofs.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fev.reinit(cell);
    fev[disp].get_function_gradients(u, grad_u);
    for (const auto& g : grad_u)
      smallest = std::min(smallest, dealii::determinant(dealii::unit_symmetric_tensor<dim>() + g));
  }
  return smallest;
}

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
  dealii::Tensor<2, dim> unit_dP[dim][dim];
  for (const auto& cell : dofs.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fev.reinit(cell);
    fev[disp].get_function_gradients(u, grad_u);
    fev[disp].get_function_gradients(v, grad_v);
    k = 0;
    r = 0;
    for (unsigned int q = 0; q < quad.size(); ++q) {
      const double jxw = fev.JxW(q) * thickness;
      const StressPoint<dim> sp(dealii::unit_symmetric_tensor<dim>() + grad_u[q], grad_v[q], out.neo_hookean, lambda,
                                mu, tau, out.rate);
      const dealii::Tensor<2, dim>& P = sp.P();
      if (out.min_J) *out.min_J = std::min(*out.min_J, dealii::determinant(sp.F()));
      for (unsigned int i = 0; i < nd; ++i) r[i] += (P * fev.shape_grad(i, q))[comp[i]] * jxw;
      if (!out.tangent) continue;
      // dP is linear in G: its values on the dim^2 unit directions e_a e_b^T give it for every
      // shape function, G_j = e_c grad N_j^T: dP(G_j) = sum_b (grad N_j)_b dP(e_c e_b^T).
      for (int a = 0; a < dim; ++a)
        for (int b = 0; b < dim; ++b) {
          dealii::Tensor<2, dim> E;
          E[a][b] = 1;
          unit_dP[a][b] = sp.dP(E);
        }
      for (unsigned int j = 0; j < nd; ++j) {
        const dealii::Tensor<1, dim> gj = fev.shape_grad(j, q);
        dealii::Tensor<2, dim> dPj;
        for (int b = 0; b < dim; ++b) dPj += gj[b] * unit_dP[comp[j]][b];
        for (unsigned int i = 0; i < nd; ++i) k(i, j) += (dPj[comp[i]] * fev.shape_grad(i, q)) * jxw;
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
