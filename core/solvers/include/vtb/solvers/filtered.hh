#pragma once
/// \file
/// The paper's approximate implicit scheme (Cai, Dill, Payandeh, Fig. 2), read as in
/// docs/method.md:
///
///   H = M (1 + dt gamma) + dt C_L + dt^2 K_L   on the free nodes (C_L, K_L: graph
///        Laplacians with edge weights c_ij, k_ij; edges to constrained nodes add to the
///        diagonal only),
///   W = H^-1 M, one scalar matrix shared by every coordinate; its rows sum to 1 on a free
///        body, so it averages accelerations.
///   F_node = Voigt forces + k_ij dt ((v_j - v_i).n) n + loads(t + dt) - gamma m v,
///   dv = dt W M^-1 F_node  (= dt H^-1 F_node: linearised backward Euler with the scalar
///        Laplacian standing in for the spring Jacobian),
///   momentum correction (free bodies): remove the linear and angular impulse that the filter
///        added, by a uniform velocity and a rigid rotation about the centre of mass,
///   v += dv, x += dt v, then the strain limit: every spring stretched beyond
///        (1 + strain_limit) L0 is shortened to it, moving free ends in inverse proportion to
///        their masses, and the velocity is updated with the move / dt.
///
/// `neighbors` keeps W_ij only for j = i and j a mesh neighbour of i (the paper), computing
/// just those entries of H^-1 by selected inversion. The truncated W loses positive
/// definiteness once dt is a few times the explicit limit, and the scheme then diverges
/// (docs/method.md derives and measures it). `full` applies the whole W = H^-1 M without
/// forming it: H is constant, so it is factorised once (sparse LDL^T) and each step does
/// two triangular solves; it is unconditionally stable for the linear problem.
///
/// `multigrid` is `full` with H^-1 replaced by one fixed symmetric V-cycle B (multigrid.hh),
/// for meshes whose factor of H is too large (3D, thousands of nodes). 0 < B <= H^-1, so
/// B^-1 = H + Delta with Delta >= 0: the step is `full`'s with the extra mass Delta, stable
/// at any dt for the linear problem as `full` is (docs/method.md; the tests compute the
/// linearised step's spectral radius).

#include "vtb/linalg/multigrid.hh"
#include "vtb/linalg/nodal_solve.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/solvers/scalar_couplings.hh"
#include "vtb/solvers/tensor_filter.hh"

#include <Eigen/SparseCore>

namespace vtb {

/// H on the free nodes (index = position in model.free_nodes), both triangles stored.
template <int dim> Eigen::SparseMatrix<double> filter_system_matrix(const Model<dim>& model, double dt);

/// W = H^-1 M (dense). For tests and the `full` filter.
template <int dim> Eigen::MatrixXd filter_matrix_full(const Model<dim>& model, double dt);

/// W = H^-1 M on the pattern of H (node and its free neighbours), row-compressed.
template <int dim>
Eigen::SparseMatrix<double, Eigen::RowMajor> filter_matrix_neighbors(const Model<dim>& model, double dt);

template <int dim> class FilteredImplicit final : public Integrator<dim> {
public:
  FilteredImplicit(const Model<dim>& model, const IntegratorOptions& options);
  void step(State<dim>& s) override;
  std::string_view name() const override { return solvers::kFiltered; }
  /// The tensor and full filters, which solve their couplings through Woodbury's identity; the
  /// multigrid filter, whose V-cycle applies a coupling as a force alone, gives the footprint's
  /// response to that force (dt^2 w^T H^-1 w by one V-cycle, kept while the footprint holds).
  bool coupling_compliance(int group, Eigen::Matrix<double, dim, dim>& out) const override;
  const std::string& filter() const { return m_filter; }
  /// Tensor filter: the steps taken by implicit Euler, its safety net for a state whose
  /// distortion is not finite (past TensorFilter::kTrustedMismatch the filter relinearises).
  long fallback_steps() const { return m_fallback_steps; }
  /// Tensor filters: the times the filter linearised again at the current shape, and the
  /// times its H was refactorised (relinearisations and covers); 0 otherwise.
  long relinearizations() const { return m_tensor ? m_tensor->relinearizations() : 0; }
  long refactorizations() const { return m_tensor ? m_tensor->refactorizations() : 0; }
  /// The correction's conjugate-gradient steps beyond its first, over the run (TensorFilter).
  long extra_corrections() const { return m_tensor ? m_tensor->extra_corrections() : 0; }
  /// Tensor filters: the steps that carried a whole refactorisation (past kHardMismatch)
  /// instead of a part of one.
  long refreshes_at_once() const { return m_tensor ? m_tensor->refreshes_at_once() : 0; }
  /// Whether it has that fallback (the tensor filters).
  bool has_fallback() const { return m_fallback_ie != nullptr; }

private:
  void finish_step(State<dim>& s);
  void correct_momentum(const State<dim>& s);
  void limit_strain(State<dim>& s) const;
  /// multigrid: unit u's w^T H^-1 w (kept in m_mg_response while it holds).
  double multigrid_response(int u) const;

  const Model<dim>& m_model;
  std::string m_filter; ///< the filter it runs (auto resolved by chosen_filter)
  bool m_full;
  std::unique_ptr<TensorFilter<dim>> m_tensor;    ///< tensor: the rest Jacobian's factor, warped
  std::unique_ptr<Integrator<dim>> m_fallback_ie; ///< tensor: implicit Euler, the safety net
  std::unique_ptr<CouplingSet<dim>> m_units;      ///< tensor, full: the couplings as their solve takes them
  bool m_fallback = false;                        ///< tensor: this step is implicit Euler's
  long m_fallback_steps = 0;
  double m_mismatch = 0; ///< tensor: this step's largest direction mismatch
  bool m_correct;
  double m_strain_limit;
  std::unique_ptr<NodalSolve> m_h;                       ///< full: the factor of H
  std::unique_ptr<SymmetricMultigrid<dim>> m_mg;         ///< multigrid: one V-cycle for H^-1
  std::vector<int> m_node_of_row;                        ///< full: factor row -> node
  std::vector<int> m_row_of_node;                        ///< full: node -> factor row (-1: fixed)
  std::unique_ptr<ScalarCouplings<dim>> m_couplings;     ///< full: pulls and contacts in the solve
  Eigen::SparseMatrix<double, Eigen::RowMajor> m_sparse; ///< neighbours: truncated W
  Nodal<dim> m_force;                                    ///< per node
  Nodal<dim> m_acc, m_dv;                                ///< per free node
  Nodal<dim> m_rhs;                                      ///< full: dim x free nodes, factor order
  /// multigrid: the couplings' units (their force stays explicit: the V-cycle's system holds no
  /// coupling) and each unit's one-step response w^T H^-1 w by one V-cycle, kept while its nodes
  /// and weights (in sum) move less than kResponseTolerance (coupling_compliance).
  struct MgResponse {
    std::array<int, CouplingSet<dim>::kMaxNodes> node{};
    std::array<double, CouplingSet<dim>::kMaxNodes> weight{};
    int size = -1;
    double value = 0;
  };
  static constexpr double kResponseTolerance = 0.02;
  std::unique_ptr<CouplingSet<dim>> m_mg_units;
  mutable std::array<MgResponse, CouplingSet<dim>::kMaxUnits> m_mg_response;
  mutable Nodal<dim> m_mg_in, m_mg_out;
};

} // namespace vtb
