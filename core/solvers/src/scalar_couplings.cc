#include "vtb/solvers/scalar_couplings.hh"

#include <cmath>

namespace vtb {

ScalarCouplings::ScalarCouplings(const NodalSolve& h, Eigen::Index rows)
    : m_h(h), m_z(Eigen::MatrixXd::Zero(rows, kMax)), m_unit(Nodal<1>::Zero(1, rows)), m_capacitance(kMax) {}

int ScalarCouplings::set(const Eigen::VectorXd& coefficient, const std::vector<int>& row_of_node) {
  int count = 0;
  bool same = true;
  std::array<int, kMax> row{};
  std::array<double, kMax> c{};
  for (Eigen::Index i = 0; i < coefficient.size() && count < kMax; ++i) {
    const int r = row_of_node[static_cast<std::size_t>(i)];
    if (r < 0 || !(coefficient[i] > 0) || !std::isfinite(coefficient[i])) continue;
    same = same && count < m_count && m_row[static_cast<std::size_t>(count)] == r;
    row[static_cast<std::size_t>(count)] = r;
    c[static_cast<std::size_t>(count++)] = coefficient[i];
  }
  same = same && count == m_count;
  if (same && c == m_c) return m_count;
  if (!same) // Z = H^-1 U: a scalar solve per coupled row
    for (int k = 0; k < count; ++k) {
      m_unit.setZero();
      m_unit(0, row[static_cast<std::size_t>(k)]) = 1.0;
      m_h.solve_in_place<1>(m_unit);
      m_z.col(k) = m_unit.row(0).transpose();
    }
  m_count = count;
  m_row = row;
  m_c = c;
  if (count == 0) return 0;
  Small S(count, count);
  for (int a = 0; a < count; ++a)
    for (int b = 0; b < count; ++b) S(a, b) = m_z(m_row[static_cast<std::size_t>(a)], b);
  for (int a = 0; a < count; ++a) S(a, a) += 1.0 / m_c[static_cast<std::size_t>(a)];
  m_capacitance.compute(S);
  return m_count;
}

} // namespace vtb
