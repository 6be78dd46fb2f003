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
  template <int dim> void solve_gathered(const Nodal<dim>& b, const int* source, Nodal<dim>& x) const {
    const auto n = static_cast<int>(m_inv_diag.size());
    double* X = x.data();
    const double* B = b.data();
    // Forward: y_i = b_i - sum_{j < i} L_ij y_j (L by rows).
    for (int i = 0; i < n; ++i) {
      const Vec<dim> sum = dot_row<dim>(m_row_ptr[static_cast<std::size_t>(i)],
                                        m_row_ptr[static_cast<std::size_t>(i) + 1], m_row_val, m_row_col, X);
      Eigen::Map<Vec<dim>>(X + i * dim) = Eigen::Map<const Vec<dim>>(B + (source ? source[i] : i) * dim) - sum;
    }
    // Diagonal and backward: x_j = y_j / d_j - sum_{i > j} L_ij x_i (L by columns).
    for (int j = n - 1; j >= 0; --j) {
      const Vec<dim> sum = dot_row<dim>(m_col_ptr[static_cast<std::size_t>(j)],
                                        m_col_ptr[static_cast<std::size_t>(j) + 1], m_col_val, m_col_row, X);
      Eigen::Map<Vec<dim>> xj(X + j * dim);
      xj = m_inv_diag[j] * xj - sum;
    }
  }

  /// Strictly lower entries of L (the fill of the factor).
  std::size_t factor_nonzeros() const { return m_col_val.size(); }

private:
  /// sum over p in [begin, end) of val[p] x(col[p]), in two interleaved sums: each row's
  /// terms then form two dependency chains of half the length (the sweeps are latency bound).
  template <int dim>
  static Vec<dim> dot_row(int begin, int end, const std::vector<double>& val, const std::vector<int>& col,
                          const double* X) {
    Vec<dim> a = Vec<dim>::Zero(), b = Vec<dim>::Zero();
    int p = begin;
    for (; p + 1 < end; p += 2) {
      a += val[static_cast<std::size_t>(p)] * Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p)] * dim);
      b += val[static_cast<std::size_t>(p) + 1] *
           Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p) + 1] * dim);
    }
    if (p < end)
      a += val[static_cast<std::size_t>(p)] * Eigen::Map<const Vec<dim>>(X + col[static_cast<std::size_t>(p)] * dim);
    return a + b;
  }

  std::vector<int> m_row_ptr, m_row_col, m_col_ptr, m_col_row;
  std::vector<double> m_row_val, m_col_val;
  Eigen::VectorXd m_inv_diag;
};

} // namespace vtb
