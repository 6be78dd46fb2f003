#pragma once
/// \file
/// Couplings from outside (a user's pull, a haptic contact, a tip's footprint) in the full
/// filter's scalar system: H' = H + U C U^T, U a column w per coupling unit (coupling_set.hh:
/// a node's unit column, or a footprint's weights) and C = diag(c) their dt^2 k + dt b
/// (isotropic, so one scalar system serves every coordinate, as H does). Solved through
/// Woodbury's identity on H's factor: x' = x - Z S^-1 U^T x with Z = H^-1 U (one scalar solve
/// per unit, made again only when the units' rows or weights change) and S = C^-1 + U^T Z.
/// Nothing is allocated after construction.

#include "vtb/linalg/nodal.hh"
#include "vtb/linalg/nodal_solve.hh"
#include "vtb/solvers/coupling_set.hh"

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace vtb {

template <int dim> class ScalarCouplings {
public:
  /// Units coupled implicitly at most; beyond them a coupling is applied as a force alone.
  static constexpr int kMax = CouplingSet<dim>::kMaxUnits;

  /// `h`: the factor of H (kept by reference); `rows`: its size.
  ScalarCouplings(const NodalSolve& h, Eigen::Index rows)
      : m_h(h), m_z(Eigen::MatrixXd::Zero(rows, kMax)), m_unit(Nodal<1>::Zero(1, rows)), m_capacitance(kMax) {}

  /// Takes the units (slots: the factor's rows). Returns how many are coupled.
  int set(const CouplingSet<dim>& set) {
    m_set = &set;
    const int count = set.units();
    std::array<double, kMax> c{};
    for (int u = 0; u < count; ++u) c[static_cast<std::size_t>(u)] = set.coefficient(u);
    const bool new_z = set.version() != m_version;
    if (!new_z && count == m_count && c == m_c) return m_count;
    if (new_z) { // Z = H^-1 U: a scalar solve per unit
      for (int u = 0; u < count; ++u) {
        m_unit.setZero();
        for (int q = 0; q < set.size(u); ++q) m_unit(0, set.slot(u, q)) += set.weight(u, q);
        m_h.solve_in_place<1>(m_unit);
        m_z.col(u) = m_unit.row(0).transpose();
      }
      m_version = set.version();
    }
    m_count = count;
    m_c = c;
    if (count == 0) return 0;
    Small S = Small::Zero(count, count);
    for (int a = 0; a < count; ++a)
      for (int q = 0; q < set.size(a); ++q) S.row(a) += set.weight(a, q) * m_z.row(set.slot(a, q)).head(count);
    for (int a = 0; a < count; ++a) m_utz[static_cast<std::size_t>(a)] = S(a, a);
    for (int a = 0; a < count; ++a) S(a, a) += 1.0 / m_c[static_cast<std::size_t>(a)];
    m_capacitance.compute(S);
    return m_count;
  }

  /// w^T H^-1 w of unit u (the couplings of the other units left out): the unit's weighted
  /// position moves by dt^2 times it per N of force on it in the next step, on every axis.
  double unit_response(int u) const { return u >= 0 && u < m_count ? m_utz[static_cast<std::size_t>(u)] : 0.0; }

  /// x <- H'^-1 b from x = H^-1 b, for each of x's dim rows (columns in the factor's order).
  void correct(Nodal<dim>& x) const {
    if (m_count == 0) return;
    for (int p = 0; p < dim; ++p) {
      SmallVec y(m_count);
      for (int u = 0; u < m_count; ++u) {
        double sum = 0;
        for (int q = 0; q < m_set->size(u); ++q) sum += m_set->weight(u, q) * x(p, m_set->slot(u, q));
        y[u] = sum;
      }
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
  const CouplingSet<dim>* m_set = nullptr;
  long m_version = -1; ///< the units' version Z was made for
  int m_count = 0;
  std::array<double, kMax> m_c{};   ///< the units' coefficients
  std::array<double, kMax> m_utz{}; ///< the units' w^T H^-1 w
  Eigen::MatrixXd m_z;              ///< rows x kMax: H^-1 U
  Nodal<1> m_unit;                  ///< a solve's scratch
  Eigen::LDLT<Small> m_capacitance; ///< C^-1 + U^T Z
};

} // namespace vtb
