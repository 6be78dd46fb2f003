#pragma once
/// \file
/// `[solver] filter = "tensor"`: the filtered step with the full rest Jacobian instead of the
/// paper's isotropic Laplacian, and stiffness warping (Mueller et al. 2002) for rotations.
///
///   H_t = M (1 + dt gamma) + dt D_0 + dt^2 K_0   (dim n x dim n on the free nodes: the spring
///        Jacobian's blocks k n n^T and c n n^T at rest, from the shared assembly),
///   dv_i = dt R_i [H_t^-1 (R^T F)]_i,
///
/// with F the filtered step's node forces and R_i the rotation of node i's neighbourhood
/// (polar part of sum_j (x_j - x_i)(X_j - X_i)^T over its mesh neighbours). For small
/// rotations it is the linearised backward Euler of implicit_euler.hh with the Jacobian frozen
/// at rest, factorised once: the scalar filter's extra mass dt (tau + dt)(K_L (x) I - K) is
/// gone, and with it the lag of the transient (docs/method.md). Allocates nothing per step.

#include "vtb/core/model.hh"
#include "vtb/core/ordered_ldlt.hh"

#include <vector>

namespace vtb {

template <int dim> class WarpedFilter {
public:
  WarpedFilter(const Model<dim>& model, double dt);
  /// dv (dim x free nodes) = dt R H_t^-1 R^T F at displacement u (F: dim x nodes).
  void apply(const Nodal<dim>& u, const Nodal<dim>& force, double dt, Nodal<dim>& dv);
  /// The rotation of each node's neighbourhood at displacement u (identity at rest).
  void rotations(const Nodal<dim>& u);
  const std::vector<Mat<dim>>& rotation() const { return m_rotation; }

private:
  const Model<dim>& m_model;
  OrderedLDLT m_h;
  std::vector<Mat<dim>> m_rotation; ///< per node
  Eigen::MatrixXd m_rhs;            ///< ordered dofs, one column
};

/// H_t on the free dofs (row dim a + p: free node a, axis p), both triangles stored.
template <int dim> Eigen::SparseMatrix<double> tensor_filter_matrix(const Model<dim>& model, double dt);

} // namespace vtb
