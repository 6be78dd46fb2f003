#pragma once
/// \file
/// The preconditioner of CVODE's Krylov path in 3D (cvode_solver.cc): Newton's matrix of the
/// spring ODE inverted exactly for the clamped Jacobian, by one Cholesky factor.

#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/model.hh"

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <vector>

namespace vtb::cvode {

/// Newton's matrix I - gamma J of the ODE below in 3D, inverted exactly for the clamped
/// Jacobian (stiffness signs: J = [[0, I], [-M^-1 K, -M^-1 D]], K's transverse term clamped
/// under compression so that the reduced matrix stays positive definite): N z = r reads
/// z1 - gamma z2 = r1 and gamma M^-1 K z1 + z2 + gamma M^-1 D z2 = r2, so
///   (M + gamma D + gamma^2 K) z2 = M r2 - gamma K r1,   z1 = r1 + gamma z2,
/// one Cholesky factor of an n x n SPD matrix (CHOLMOD supernodal) where KLU's LU of the
/// 2n x 2n block system fills in. GMRES, preconditioned by it, takes what the clamp and the
/// dashpots' omitted terms leave. K, D and P share one pattern (the node blocks and the spring
/// blocks between free nodes), so a refresh writes values through offsets kept at construction.
template <int dim> class ReducedNewton {
public:
  explicit ReducedNewton(const Model<dim>& model) : m_model(model) {
    const auto& net = model.net;
    const int nf = static_cast<int>(model.free_nodes.size()), n = dim * nf;
    m_K = free_block_pattern(net, model.free_index, nf);
    m_D = m_K;
    m_P = m_K;
    // Offsets of every spring's four blocks, in for_each_jacobian_block's order (ii, jj, ij, ji).
    m_offset.assign(static_cast<std::size_t>(net.num_springs()) * 4 * dim * dim, -1);
    for (int sp = 0; sp < net.num_springs(); ++sp) {
      const int i = net.edge[static_cast<std::size_t>(sp)][0], j = net.edge[static_cast<std::size_t>(sp)][1];
      const int fa = model.free_index[static_cast<std::size_t>(i)], fb = model.free_index[static_cast<std::size_t>(j)];
      const int rows[4] = {fa, fb, fa, fb}, cols[4] = {fa, fb, fb, fa};
      for (int w = 0; w < 4; ++w) {
        if (rows[w] < 0 || cols[w] < 0) continue;
        for (int p = 0; p < dim; ++p)
          for (int q = 0; q < dim; ++q)
            m_offset[static_cast<std::size_t>(((sp * 4 + w) * dim + p) * dim + q)] =
                offset(rows[w] * dim + p, cols[w] * dim + q);
      }
    }
    // The volume term's: every cell's (dim + 1)^2 blocks (its node pairs are springs: in the pattern).
    constexpr int nb = (dim + 1) * (dim + 1) * dim * dim;
    m_cell_offset.assign(static_cast<std::size_t>(net.volume.size()) * nb, -1);
    for (int c = 0; c < net.volume.size(); ++c)
      for (int x = 0; x <= dim; ++x)
        for (int y = 0; y <= dim; ++y) {
          const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
          const int fa = model.free_index[static_cast<std::size_t>(cell[x])];
          const int fb = model.free_index[static_cast<std::size_t>(cell[y])];
          if (fa < 0 || fb < 0) continue;
          for (int p = 0; p < dim; ++p)
            for (int q = 0; q < dim; ++q)
              m_cell_offset[static_cast<std::size_t>(c * nb + ((x * (dim + 1) + y) * dim + p) * dim + q)] =
                  offset(fa * dim + p, fb * dim + q);
        }
    m_mass.resize(n);
    m_diag.resize(static_cast<std::size_t>(n));
    for (int a = 0; a < nf; ++a)
      for (int p = 0; p < dim; ++p) {
        m_mass[a * dim + p] = net.mass[model.free_nodes[static_cast<std::size_t>(a)]];
        m_diag[static_cast<std::size_t>(a * dim + p)] = offset(a * dim + p, a * dim + p);
      }
    m_b.resize(n);
    m_x.resize(n);
  }

  /// K and D at displacement u when `refresh` (else those of the last refresh: CVODE's jok),
  /// then P = M + gamma D + gamma^2 K factorised. False when P is not positive definite (a
  /// non-finite state): CVODE then retries with a smaller step.
  bool setup(const Nodal<dim>& u, bool refresh, double gamma) {
    const auto& net = m_model.net;
    if (refresh) {
      std::fill(m_K.valuePtr(), m_K.valuePtr() + m_K.nonZeros(), 0.0);
      std::fill(m_D.valuePtr(), m_D.valuePtr() + m_D.nonZeros(), 0.0);
      for_each_jacobian_block(net, u, true,
                              [&](int sp, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
                                const int e0 = net.edge[static_cast<std::size_t>(sp)][0];
                                const int w = i == j ? (i == e0 ? 0 : 1) : (i == e0 ? 2 : 3);
                                const long* at = &m_offset[static_cast<std::size_t>((sp * 4 + w) * dim * dim)];
                                if (at[0] < 0) return;
                                for (int p = 0; p < dim; ++p)
                                  for (int q = 0; q < dim; ++q) {
                                    m_K.valuePtr()[at[p * dim + q]] -= sign * K(p, q);
                                    m_D.valuePtr()[at[p * dim + q]] -= sign * D(p, q);
                                  }
                              });
      constexpr int nb = (dim + 1) * (dim + 1) * dim * dim;
      for_each_cell_block(
          net.volume, net.rest, u, true, [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>& D) {
            const long* at = &m_cell_offset[static_cast<std::size_t>(c * nb + (x * (dim + 1) + y) * dim * dim)];
            if (at[0] < 0) return;
            for (int p = 0; p < dim; ++p)
              for (int q = 0; q < dim; ++q) {
                m_K.valuePtr()[at[p * dim + q]] -= K(p, q);
                m_D.valuePtr()[at[p * dim + q]] -= D(p, q);
              }
          });
      for (std::size_t d = 0; d < m_diag.size(); ++d)
        m_D.valuePtr()[m_diag[d]] += net.mass_damping * m_mass[static_cast<Eigen::Index>(d)];
    }
    const double* k = m_K.valuePtr();
    const double* c = m_D.valuePtr();
    double* pv = m_P.valuePtr();
    m_gamma = gamma;
    for (Eigen::Index e = 0; e < m_P.nonZeros(); ++e) pv[e] = gamma * (c[e] + gamma * k[e]);
    for (std::size_t d = 0; d < m_diag.size(); ++d) pv[m_diag[d]] += m_mass[static_cast<Eigen::Index>(d)];
    if (!m_analysed) {
      m_llt.analyzePattern(m_P);
      m_analysed = true;
    }
    m_llt.factorize(m_P);
    return m_llt.info() == Eigen::Success;
  }

  /// z = N^-1 r for the gamma of the last setup, the matrix its factor holds (CVODE may call with
  /// a gamma that has moved since; the factor's inverse is still the preconditioner it asked for).
  void solve(const double* r, double* z) {
    const double gamma = m_gamma;
    const Eigen::Index n = m_b.size();
    const Eigen::Map<const Eigen::VectorXd> r1(r, n), r2(r + n, n);
    m_b.noalias() = m_mass.cwiseProduct(r2);
    m_b.noalias() -= gamma * (m_K * r1);
    m_x = m_llt.solve(m_b);
    Eigen::Map<Eigen::VectorXd>(z + n, n) = m_x;
    Eigen::Map<Eigen::VectorXd>(z, n) = r1 + gamma * m_x;
  }

private:
  long offset(int row, int col) const {
    const int* begin = m_K.innerIndexPtr() + m_K.outerIndexPtr()[col];
    const int* end = m_K.innerIndexPtr() + m_K.outerIndexPtr()[col + 1];
    return static_cast<long>(std::lower_bound(begin, end, row) - m_K.innerIndexPtr());
  }

  const Model<dim>& m_model;
  Eigen::SparseMatrix<double> m_K, m_D, m_P; ///< one pattern; stiffness signs (K, D positive)
  std::vector<long> m_offset;                ///< per spring, block and entry: the value's offset, -1 off the free dofs
  std::vector<long> m_cell_offset;           ///< per cell, block (a, b) and entry: as m_offset
  std::vector<long> m_diag;                  ///< per free dof: its diagonal's offset
  Eigen::VectorXd m_mass, m_b, m_x;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> m_llt;
  bool m_analysed = false;
  double m_gamma = 0; ///< of the factor
};

} // namespace vtb::cvode
