#pragma once
/// \file
/// Selected inversion: the entries of A^-1 on the sparsity pattern of A, without forming
/// A^-1. The paper's neighbour filter needs exactly these entries of H^-1.

#include <Eigen/SparseCore>

namespace vtb {

/// For a symmetric positive definite A (both triangles stored), returns the matrix with
/// A's pattern holding the corresponding entries of A^-1. Uses Eigen's sparse LDL^T with
/// AMD ordering, then the Takahashi-Fagan-Chen (1973) recurrence on the factor's pattern:
///   Z_ij = -sum_{k in L(:,j)} Z_ik L_kj  (i in L(:,j)),   Z_jj = 1/d_j - sum_k L_kj Z_kj,
/// from the last column to the first. Cost is sum_j |L(:,j)|^2, far below a full inverse.
/// Throws std::runtime_error if A is not positive definite.
Eigen::SparseMatrix<double> selected_inverse(const Eigen::SparseMatrix<double>& A);

} // namespace vtb
