#pragma once
/// \file
/// Couplings from outside (a user's pull, a haptic contact) in the full filter's scalar
/// system: H' = H + U C U^T, U the unit columns of up to kMax coupled rows and C = diag(c) their
/// dt^2 k + dt b (isotropic, so one scalar system serves every coordinate, as H does). Solved
/// through Woodbury's identity on H's factor: x' = x - Z S^-1 U^T x with Z = H^-1 U (one
/// scalar solve per coupled row, made again only when the rows change) and S = C^-1 + U^T Z.
/// Nothing is allocated after construction.

#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/nodal_solve.hh"

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace vtb {

class ScalarCouplings {
public:
  /// Rows coupled implicitly at most; beyond them a coupling is applied as a force alone.
  static constexpr int kMax = 8;

  /// `h`: the factor of H (kept by reference); `rows`: its size.
  ScalarCouplings(const NodalSolve& h, Eigen::Index rows);

  /// Takes the couplings' coefficients per node (dt^2 k + dt b; 0 = none) and each node's row
  /// in the factor (-1: not a row, e.g. a fixed node). Returns how many rows are coupled.
  int set(const Eigen::VectorXd& coefficient, const std::vector<int>& row_of_node);

  /// x <- H'^-1 b from x = H^-1 b, for each of x's dim rows (columns in the factor's order).
  template <int dim> void correct(Nodal<dim>& x) const {
    if (m_count == 0) return;
    for (int p = 0; p < dim; ++p) {
      SmallVec y(m_count);
      for (int r = 0; r < m_count; ++r) y[r] = x(p, m_row[static_cast<std::size_t>(r)]);
      y = m_capacitance.solve(y);
      for (Eigen::Index i = 0; i < x.cols(); ++i) {
        double sum = 0;
        for (int c = 0; c < m_count; ++c) sum += m_z(i, c) * y[c];
        x(p, i) -= sum;
      }
    }
  }

private:
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMax, kMax>;
  using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMax, 1>;
  const NodalSolve& m_h;
  int m_count = 0;
  std::array<int, kMax> m_row{};    ///< the coupled rows
  std::array<double, kMax> m_c{};   ///< and their coefficients
  Eigen::MatrixXd m_z;              ///< rows x kMax: H^-1 U
  Nodal<1> m_unit;                  ///< a solve's scratch
  Eigen::LDLT<Small> m_capacitance; ///< C^-1 + U^T Z
};

} // namespace vtb
