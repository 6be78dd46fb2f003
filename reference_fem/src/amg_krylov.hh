#pragma once
// Internal to reference_fem: the iterative solve of the FEM's systems, for both backends
// (backends.hh). Conjugate gradients (GMRES where CG does not converge: a tangent past a limit
// point is indefinite) preconditioned by Trilinos ML's smoothed-aggregation algebraic multigrid,
// handed elasticity's near-null space: the rigid-body modes at the dofs' support points (three
// in 2D, six in 3D). Without the rotations the coarse spaces cannot represent a bending mode
// and the iteration count grows with the mesh (test FemAmg.RigidBodyModesBoundTheIterations).
//
// ML takes a Trilinos copy of each matrix it builds a hierarchy for (the serial backend's are
// deal.II SparseMatrix; the copy is on MPI_COMM_SELF, and MPI is initialised on first use, once
// per process, as Trilinos needs it: ensure_mpi below).
#include <deal.II/base/index_set.h>
#include <deal.II/base/point.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <Teuchos_ParameterList.hpp>
#include <ml_MultiLevelPreconditioner.h>

#include <cmath>

#include <mpi.h>

#include <memory>
#include <mutex>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace vtb::fem {

/// MPI for a serial process that uses Trilinos: initialised once (thread-multiple, so that two
/// serial FEMs may run on two threads), never finalised by vtb (the process's exit ends it).
inline void ensure_mpi() {
  static std::once_flag once; // process-wide by nature: MPI_Init may be called once per process
  std::call_once(once, [] {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided);
    }
  });
}

/// The near-null space of elasticity at the given dofs (their support points and components):
/// dim translations, then the dim (dim - 1) / 2 rotations about the body's centre, scaled by its
/// size so that every mode has entries of order one. Column-major, one column per mode, one row
/// per dof of `owned` in its order (the matrix's local rows).
template <int dim>
std::vector<double> rigid_body_modes(const dealii::IndexSet& owned, const std::vector<dealii::Point<dim>>& point,
                                     const std::vector<int>& comp, const dealii::Point<dim>& centre, double size,
                                     bool rotations) {
  const int n_modes = rotations ? dim * (dim + 1) / 2 : dim;
  const std::size_t n = owned.n_elements();
  std::vector<double> modes(n * static_cast<std::size_t>(n_modes), 0.0);
  std::size_t i = 0;
  for (const auto d : owned) {
    const int c = comp[d];
    const dealii::Tensor<1, dim> x = (point[d] - centre) / size;
    modes[static_cast<std::size_t>(c) * n + i] = 1;
    if (rotations) {
      // Rotation about axis r (3D) or the plane's normal (2D): the velocity e_r x x.
      if constexpr (dim == 2) {
        modes[2 * n + i] = c == 0 ? -x[1] : x[0];
      } else {
        const int a = (c + 1) % 3, b = (c + 2) % 3;             // (e_r x x)_c = eps_{c r k} x_k, (c, a, b) cyclic
        modes[static_cast<std::size_t>(3 + a) * n + i] = x[b];  // r = a: eps_{c a b} = +1
        modes[static_cast<std::size_t>(3 + b) * n + i] = -x[a]; // r = b: eps_{c b a} = -1
      }
    }
    ++i;
  }
  return modes;
}

/// Counts of one solver's work, for summary.json and docs/fem.md.
struct KrylovStats {
  long setups = 0, solves = 0, iterations = 0, max_iterations = 0;
};

template <class Matrix, class Vector> class AmgKrylov {
public:
  /// The modes (rigid_body_modes) and the number of components per support point.
  void set_null_space(std::vector<double> modes, int n_modes, int components) {
    m_modes = std::move(modes);
    m_n_modes = n_modes;
    m_components = components;
  }
  /// The null space and tolerance of another (a second system of the same dofs).
  void copy_settings(const AmgKrylov& o) {
    m_modes = o.m_modes;
    m_n_modes = o.m_n_modes;
    m_components = o.m_components;
    m_tolerance = o.m_tolerance;
  }
  /// Relative residual of every solve: |b - A x| <= tolerance |b|.
  void set_tolerance(double tolerance) { m_tolerance = tolerance; }

  /// Builds the multigrid hierarchy for A (kept until the next factor).
  void factor(const Matrix& A) {
    m_A = &A;
    Teuchos::ParameterList p;
    ML_Epetra::SetDefaults("SA", p);
    p.set("ML output", 0);
    p.set("aggregation: type", "Uncoupled");
    p.set("smoother: type", "Chebyshev");
    p.set("smoother: sweeps", 2);
    p.set("coarse: type", "Amesos-KLU");
    p.set("coarse: max size", 2000);
    p.set("PDE equations", m_components);
    p.set("null space: type", "pre-computed");
    p.set("null space: dimension", m_n_modes);
    p.set("null space: vectors", m_modes.data());
    p.set("null space: add default vectors", false);
    ensure_mpi(); // before any Trilinos object: they hold an MPI communicator
    m_amg = std::make_unique<dealii::TrilinosWrappers::PreconditionAMG>();
    // ML's finest level and smoother read the matrix it was built on: a copy, so that a kept
    // hierarchy stays one consistent preconditioner while Newton reassembles its tangent (on
    // the matrix itself, a stale hierarchy with a new fine level diverged).
    m_copy = std::make_unique<dealii::TrilinosWrappers::SparseMatrix>();
    if constexpr (std::is_same_v<Matrix, dealii::SparseMatrix<double>>)
      m_copy->reinit(A, 0.0);
    else
      m_copy->copy_from(A);
    m_amg->initialize(*m_copy, p);
    ++m_stats.setups;
    m_first_rate = -1;
  }

  /// x = A^-1 b from x = 0: CG, then (if CG did not converge) GMRES from CG's last iterate.
  void solve(Vector& x, const Vector& b) {
    const double target = m_tolerance * b.l2_norm();
    x = 0;
    if (target == 0) return;
    dealii::SolverControl control(kMaxIterations, target, false, false);
    try {
      dealii::SolverCG<Vector> cg(control);
      cg.solve(*m_A, x, b, *m_amg);
    } catch (const dealii::SolverControl::NoConvergence&) {
      dealii::SolverControl again(kMaxIterations, target, false, false);
      typename dealii::SolverGMRES<Vector>::AdditionalData data(100, true);
      dealii::SolverGMRES<Vector> gmres(again, data);
      try {
        gmres.solve(*m_A, x, b, *m_amg);
      } catch (const dealii::SolverControl::NoConvergence&) {
        throw std::runtime_error("fem: the AMG-preconditioned Krylov solve did not converge in " +
                                 std::to_string(2 * kMaxIterations) + " iterations");
      }
      count(control.last_step() + again.last_step());
      return;
    }
    count(control.last_step());
  }

  /// For a sequence of matrices of one pattern (Newton's tangents): keeps the hierarchy while the
  /// last solve took at most 1.5x (plus 5) the iterations the first solve after its setup would
  /// have taken to the last one's tolerance (iterations per decade of residual reduction, so that
  /// a Newton whose tolerances vary compares like with like), else rebuilds.
  void update(const Matrix& A) {
    if (m_A != &A || m_first_rate < 0 || m_last > 1.5 * m_first_rate * m_last_decades + 5) {
      factor(A);
      m_first_rate = -1;
    }
  }

  const KrylovStats& stats() const { return m_stats; }
  long last_iterations() const { return m_last; }

private:
  static constexpr unsigned int kMaxIterations = 2000;
  void count(unsigned int it) {
    m_last = it;
    m_last_decades = std::max(1.0, -std::log10(m_tolerance));
    if (m_first_rate < 0) m_first_rate = static_cast<double>(it) / m_last_decades;
    ++m_stats.solves;
    m_stats.iterations += it;
    m_stats.max_iterations = std::max<long>(m_stats.max_iterations, it);
  }
  std::vector<double> m_modes;
  int m_n_modes = 0, m_components = 1;
  double m_tolerance = 1e-12;
  const Matrix* m_A = nullptr;
  std::unique_ptr<dealii::TrilinosWrappers::SparseMatrix> m_copy;
  std::unique_ptr<dealii::TrilinosWrappers::PreconditionAMG> m_amg; ///< made in factor (after ensure_mpi)
  KrylovStats m_stats;
  long m_last = 0;
  double m_last_decades = 1, m_first_rate = -1; ///< the first solve after the setup: iterations per decade
};

/// A backend's direct solver or AmgKrylov, chosen once per run (KelvinVoigtProblem::choose_solvers).
template <class Direct, class Matrix, class Vector> struct ChosenSolver {
  Direct direct;
  AmgKrylov<Matrix, Vector> amg;
  bool iterative = false;
  void factor(const Matrix& A) { iterative ? amg.factor(A) : direct.factor(A); }
  /// A new matrix of the same pattern: a direct solver refactors, the AMG may keep its hierarchy.
  void update(const Matrix& A) { iterative ? amg.update(A) : direct.factor(A); }
  void solve(Vector& x, const Vector& b) { iterative ? amg.solve(x, b) : direct.solve(x, b); }
};

} // namespace vtb::fem
