#pragma once
/// \file
/// The LDL^T factor of one scalar matrix (OrderedLDLT) applied to dim right-hand sides at
/// once, stored node by node: x is a dim x n Nodal whose column k is the k-th row of the
/// factor's ordering. The filtered step solves H X = F for all coordinates with the one scalar
/// factor of H; Eigen's sparse triangular solve sweeps L once per right-hand side and scatters
/// in the forward sweep. Here L is kept by rows for the forward sweep and by columns for the
/// backward sweep, so that both are gathers that accumulate a node's dim values in registers
/// and each sweep reads L once (docs/performance.md measures it). Allocates nothing per solve.

#include "vtb/core/nodal.hh"
#include "vtb/core/ordered_ldlt.hh"

#include <vector>

namespace vtb {

class NodalSolve {
public:
  /// Copies the factor of `factor`, which must be factorised.
  explicit NodalSolve(const OrderedLDLT& factor);

  /// x <- A^-1 x for each of the dim rows of x (columns in the factor's ordering).
  template <int dim> void solve_in_place(Nodal<dim>& x) const {
    const auto n = static_cast<int>(m_inv_diag.size());
    double* X = x.data();
    // Forward: y_i = x_i - sum_{j < i} L_ij y_j (L by rows).
    for (int i = 0; i < n; ++i) {
      Vec<dim> acc = Eigen::Map<const Vec<dim>>(X + i * dim);
      for (int p = m_row_ptr[static_cast<std::size_t>(i)]; p < m_row_ptr[static_cast<std::size_t>(i) + 1]; ++p)
        acc -= m_row_val[static_cast<std::size_t>(p)] *
               Eigen::Map<const Vec<dim>>(X + m_row_col[static_cast<std::size_t>(p)] * dim);
      Eigen::Map<Vec<dim>>(X + i * dim) = acc;
    }
    // Diagonal and backward: x_j = y_j / d_j - sum_{i > j} L_ij x_i (L by columns).
    for (int j = n - 1; j >= 0; --j) {
      Vec<dim> acc = m_inv_diag[j] * Eigen::Map<const Vec<dim>>(X + j * dim);
      for (int p = m_col_ptr[static_cast<std::size_t>(j)]; p < m_col_ptr[static_cast<std::size_t>(j) + 1]; ++p)
        acc -= m_col_val[static_cast<std::size_t>(p)] *
               Eigen::Map<const Vec<dim>>(X + m_col_row[static_cast<std::size_t>(p)] * dim);
      Eigen::Map<Vec<dim>>(X + j * dim) = acc;
    }
  }

  /// Strictly lower entries of L (the fill of the factor).
  std::size_t factor_nonzeros() const { return m_col_val.size(); }

private:
  std::vector<int> m_row_ptr, m_row_col, m_col_ptr, m_col_row;
  std::vector<double> m_row_val, m_col_val;
  Eigen::VectorXd m_inv_diag;
};

} // namespace vtb
