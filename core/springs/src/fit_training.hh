#pragma once
/// \file
/// What the spring fit trains on (fitted_springs.cc): the solver of the pinned FEM stiffness, and
/// the training set of loads and the FEM's answers to them (fit_training.cc).

#include "vtb/base/input_error.hh"
#include "vtb/springs/fitted_springs.hh"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <vector>

namespace vtb::fit {

using SpMat = Eigen::SparseMatrix<double>;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Triplets = std::vector<Eigen::Triplet<double>>;

/// Solves with a symmetric matrix whose pinned dofs are held at zero. Their rows and columns
/// are made the identity's in the matrix itself, which CHOLMOD then reads in place (its lower
/// triangle): no reduced copy of the matrix, no map into one, no reduced right-hand sides
/// (on the 10k-node slab's fit 14 MB at its peak; docs/fidelity.md).
class PinnedSolver {
public:
  PinnedSolver(int dofs, const std::vector<int>& pins) : m_pinned(static_cast<std::size_t>(dofs), false) {
    for (int d : pins) m_pinned[static_cast<std::size_t>(d)] = true;
  }
  /// Factorises `a` (full, compressed, the mesh's pattern), its pinned rows and columns set to
  /// the identity's first. Every matrix has the first one's pattern (one analysis).
  void factorize(SpMat& a) {
    const int* outer = a.outerIndexPtr();
    if (!a.isCompressed() || (m_analysed && !std::equal(m_outer.begin(), m_outer.end(), outer)))
      throw std::logic_error("PinnedSolver: a matrix of another pattern than the mesh's");
    for (int col = 0; col < a.outerSize(); ++col)
      for (SpMat::InnerIterator it(a, col); it; ++it)
        if (m_pinned[static_cast<std::size_t>(it.row())] || m_pinned[static_cast<std::size_t>(col)])
          it.valueRef() = it.row() == col ? 1.0 : 0.0;
    if (!m_analysed) {
      m_outer.assign(outer, outer + a.outerSize() + 1);
      m_llt.analyzePattern(a);
      m_analysed = true;
    }
    m_llt.factorize(a);
    if (m_llt.info() != Eigen::Success)
      throw InputError("[solver].springs = \"fitted\": the mesh's stiffness is singular with its rigid motions "
                       "pinned (is the mesh in one piece?)");
  }
  /// b <- K^-1 b (pinned rows zero), kSolveColumns columns at a time (CHOLMOD's supernodal
  /// solve of a block): every block the fit solves (its 30 training loads, the modes' 45
  /// columns) in one call, so that each supernode's panel is packed once for all of them.
  void solve_in_place(MatrixXd& b) const {
    for (Eigen::Index d = 0; d < b.rows(); ++d)
      if (m_pinned[static_cast<std::size_t>(d)]) b.row(d).setZero();
    for (Eigen::Index c0 = 0; c0 < b.cols(); c0 += kSolveColumns) {
      const Eigen::Index w = std::min<Eigen::Index>(kSolveColumns, b.cols() - c0);
      b.middleCols(c0, w) = m_llt.solve(b.middleCols(c0, w));
    }
  }
  MatrixXd solve(const MatrixXd& rhs) const {
    MatrixXd x = rhs;
    solve_in_place(x);
    return x;
  }

private:
  /// At 16 columns a call, OpenBLAS's packing of the factor's panels took a fifth of the 50k-node
  /// fit (perf); at 48 the 10k slab's fit took 25.3-25.7 s against 30.2-30.3 s, the 50k slab's
  /// 241 s against 295 s, its peak 1.39 GB against 1.33 (docs/fidelity.md).
  static constexpr Eigen::Index kSolveColumns = 48;
  std::vector<bool> m_pinned;
  /// CHOLMOD's supernodal Cholesky (its ordering: AMD or METIS, whichever fills less). On a
  /// 10k-node CGAL slab (29,337 unknowns, 8.7M entries in L with METIS) it factorises in 0.7 s
  /// with OpenBLAS where Eigen's simplicial LDL^T took 13-16 s, and solves 30 right-hand sides
  /// in 0.2 s (docs/fidelity.md).
  Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower> m_llt;
  bool m_analysed = false;
  std::vector<int> m_outer; ///< the first matrix's column starts, to hold later matrices to it
};

/// The training set: M-orthonormal lowest non-rigid modes of the free mesh, projected off the
/// rigid motions (or of the supported body), scaled (targets T), their loads F = K_fem T, the
/// orthonormal rigid basis Q (no columns for a supported body), and the pins that make the
/// stiffnesses invertible (the supports' dofs, or a statically determinate set). Tv and Fv
/// are the held-out modes and their loads (the validation).
struct Training {
  MatrixXd Q, T, F, Tv, Fv;
  std::vector<int> pins;
  bool supported = false;
};

template <int dim>
Training training_set(const Mesh<dim>& mesh, double E, double nu, double thickness, int modes, const FitOptions& o);

} // namespace vtb::fit
