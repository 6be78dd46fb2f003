#pragma once
/// \file
/// The LDL^T factor of one scalar matrix (OrderedLDLT) applied to dim right-hand sides at
/// once, stored node by node: x is a dim x n Nodal whose column k is the k-th row of the
/// factor's ordering. The filtered step solves H X = F for all coordinates with the one scalar
/// factor of H; Eigen's sparse triangular solve sweeps L once per right-hand side and scatters
/// in the forward sweep. Here L is kept by rows for the forward sweep and by columns for the
/// backward sweep, so that both are gathers that accumulate a node's dim values in registers
/// and each sweep reads L once (docs/performance.md measures it). Allocates nothing per solve.

#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/ordered_ldlt.hh"

#include <vector>

namespace vtb {

class NodalSolve {
public:
  /// Copies the factor of `factor`, which must be factorised.
  explicit NodalSolve(const OrderedLDLT& factor);

  /// x <- A^-1 x for each of the dim rows of x (columns in the factor's ordering).
  template <int dim> void solve_in_place(Nodal<dim>& x) const { solve_gathered<dim>(x, nullptr, x); }

  /// x <- A^-1 b with b's column source[r] as the factor's row r (the forward sweep gathers
  /// it, so that no separate pass reorders b); source = nullptr: b's columns in factor order.
  template <int dim> void solve_gathered(const Nodal<dim>& b, const int* source, Nodal<dim>& x) const;

  /// Strictly lower entries of L (the fill of the factor).
  std::size_t factor_nonzeros() const { return m_col_val.size(); }

private:
  std::vector<int> m_row_ptr, m_row_col, m_col_ptr, m_col_row;
  std::vector<double> m_row_val, m_col_val;
  Eigen::VectorXd m_inv_diag;
};

} // namespace vtb
