#pragma once
// Internal to reference_fem: the two linear-algebra backends of the one Kelvin-Voigt solver
// (kelvin_voigt_problem.hh). Everything the solver does is written once against this
// interface; a backend only says how the triangulation is made and distributed, which
// matrices, vectors and direct solver hold the numbers, and how ranks are summed.
//   Serial: deal.II's Triangulation and SparseMatrix; CHOLMOD's supernodal Cholesky for the
//     symmetric positive definite systems (the linear step's A0, the mass), UMFPACK for the
//     nonlinear tangent; never touches MPI, so a plain `vtb run` needs no MPI initialisation.
//   Distributed: parallel::fullydistributed::Triangulation (the distributed triangulation that
//     takes simplices), Trilinos matrices and vectors and Trilinos' direct solver, under mpirun.
// Either backend's systems may instead go to AMG-preconditioned CG (amg_krylov.hh), chosen per
// run (KelvinVoigtProblem::choose_solvers).

#include "grid.hh"

#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/tria.h>
#include <deal.II/grid/tria_description.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>
#include <deal.II/lac/vector.h>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <memory>
#include <stdexcept>
#include <vector>

namespace vtb::fem {

template <int dim> struct SerialBackend {
  using Tria = dealii::Triangulation<dim>;
  using Vector = dealii::Vector<double>;
  using Matrix = dealii::SparseMatrix<double>;

  struct Solver {
    dealii::SparseDirectUMFPACK lu;
    void factor(const Matrix& A) { lu.initialize(A); }
    void solve(Vector& x, const Vector& b) { lu.vmult(x, b); }
  };
  /// For symmetric positive definite matrices: CHOLMOD's supernodal Cholesky of a copy in
  /// Eigen's format. Against UMFPACK (an LU that ignores the symmetry) on P2 in 3D: half the
  /// fill and a BLAS-3 factorisation (docs/fem.md measures it).
  struct SpdSolver {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt;
    Eigen::VectorXd rhs, sol;
    void factor(const Matrix& A) {
      std::vector<Eigen::Triplet<double>> t;
      t.reserve(A.n_nonzero_elements());
      for (auto it = A.begin(); it != A.end(); ++it)
        if (it->column() <= it->row()) // the lower triangle is what the factorisation reads
          t.emplace_back(static_cast<int>(it->row()), static_cast<int>(it->column()), it->value());
      Eigen::SparseMatrix<double> E(static_cast<Eigen::Index>(A.m()), static_cast<Eigen::Index>(A.n()));
      E.setFromTriplets(t.begin(), t.end());
      llt.compute(E);
      if (llt.info() != Eigen::Success)
        throw std::runtime_error("fem: the system matrix is not positive definite (CHOLMOD)");
      rhs.resize(E.rows());
    }
    void solve(Vector& x, const Vector& b) {
      for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs[i] = b[static_cast<dealii::types::global_dof_index>(i)];
      sol = llt.solve(rhs);
      for (Eigen::Index i = 0; i < rhs.size(); ++i) x[static_cast<dealii::types::global_dof_index>(i)] = sol[i];
    }
  };

  explicit SerialBackend(MPI_Comm /*unused: one process*/) {}
  static std::unique_ptr<Tria> make_tria(MPI_Comm) { return std::make_unique<Tria>(); }
  void create(const Problem<dim>& model, int refinements, Tria& tria, std::vector<std::vector<int>>& loads_of_id) {
    make_triangulation(model, refinements, tria, loads_of_id);
  }
  void reinit(dealii::DynamicSparsityPattern& dsp, const dealii::IndexSet& /*owned*/,
              const dealii::IndexSet& /*relevant*/, const std::vector<Matrix*>& matrices) {
    pattern.copy_from(dsp);
    for (auto* A : matrices) A->reinit(pattern);
  }
  static void reinit(Vector& v, const dealii::IndexSet& owned) { v.reinit(owned.size()); }
  /// A copy of u that reads every dof of the cells this process owns (all of them here).
  static void reinit_ghosted(Vector& g, const dealii::IndexSet& owned, const dealii::IndexSet&) {
    g.reinit(owned.size());
  }
  static void sum(std::vector<double>&) {}
  static double max(double x) { return x; }
  static int ranks() { return 1; }

  dealii::SparsityPattern pattern;
};

template <int dim> struct DistributedBackend {
  using Tria = dealii::parallel::fullydistributed::Triangulation<dim>;
  using Vector = dealii::TrilinosWrappers::MPI::Vector;
  using Matrix = dealii::TrilinosWrappers::SparseMatrix;

  struct Solver {
    dealii::SolverControl control{1, 0};
    dealii::TrilinosWrappers::SolverDirect direct{control};
    void factor(const Matrix& A) { direct.initialize(A); }
    void solve(Vector& x, const Vector& b) { direct.solve(x, b); }
  };
  using SpdSolver = Solver;

  explicit DistributedBackend(MPI_Comm c) : comm(c) {}
  static std::unique_ptr<Tria> make_tria(MPI_Comm c) { return std::make_unique<Tria>(c); }
  /// The serial triangulation (identical on every rank), partitioned, then distributed.
  void create(const Problem<dim>& model, int refinements, Tria& tria, std::vector<std::vector<int>>& loads_of_id) {
    dealii::Triangulation<dim> serial;
    make_triangulation(model, refinements, serial, loads_of_id);
    dealii::GridTools::partition_triangulation(dealii::Utilities::MPI::n_mpi_processes(comm), serial);
    tria.create_triangulation(
        dealii::TriangulationDescription::Utilities::create_description_from_triangulation(serial, comm));
  }
  void reinit(dealii::DynamicSparsityPattern& dsp, const dealii::IndexSet& owned, const dealii::IndexSet& relevant,
              const std::vector<Matrix*>& matrices) {
    dealii::SparsityTools::distribute_sparsity_pattern(dsp, owned, comm, relevant);
    for (auto* A : matrices) A->reinit(owned, owned, dsp, comm);
  }
  void reinit(Vector& v, const dealii::IndexSet& owned) const { v.reinit(owned, comm); }
  void reinit_ghosted(Vector& g, const dealii::IndexSet& owned, const dealii::IndexSet& relevant) const {
    g.reinit(owned, relevant, comm);
  }
  void sum(std::vector<double>& v) const { dealii::Utilities::MPI::sum(v, comm, v); }
  double max(double x) const { return dealii::Utilities::MPI::max(x, comm); }
  int ranks() const { return static_cast<int>(dealii::Utilities::MPI::n_mpi_processes(comm)); }

  MPI_Comm comm;
};

} // namespace vtb::fem
