#pragma once
/// \file
/// The reference trajectory of the discrete spring model: SUNDIALS CVODE (BDF, Newton) on
///   u' = v,   M v' = f_int(u, v) + f_ext(t)
/// over the free nodes (supports prescribe u and v inside the right-hand side), with the
/// analytic sparse Jacobian [[0, I], [M^-1 K, M^-1 C]] (K the exact spring Jacobian, C the
/// dashpots', the dependence of the dashpot direction on x omitted) solved by KLU; or (3D, by
/// default) Newton's systems solved by GMRES, preconditioned by their exact inverse for the
/// clamped Jacobian: the 2 x 2 block system reduced to the SPD M + gamma D + gamma^2 K, which
/// CHOLMOD factorises (docs/harness.md, "CVODE's linear solver").

#include "vtb/solvers/simulation.hh"

#include <string>

namespace vtb {

/// The scene's CVODE settings (rtol, atol) as they are, and what a caller may ask beyond them.
struct CvodeOptions : CvodeSettings {
  long max_steps = 2'000'000; ///< CVODE steps in the whole run before it gives up
  /// Newton's linear solver: "auto" (klu in 2D, gmres in 3D), "klu" (the 2n x 2n system by
  /// sparse LU) or "gmres" (GMRES preconditioned by the reduced system's Cholesky factor). KLU's
  /// LU of the 3D block system fills in: on a 2,415-node tissue block a CVODE step cost 1.8 s.
  std::string linear_solver = "auto";
};

/// Integrates the model to each sample time (CVODE's own dense output: exact at the
/// sample times). RunReport.extra holds CVODE's statistics (steps, Newton iterations,
/// Jacobian evaluations, error-test failures, nonlinear convergence failures). A failure
/// (too much work, repeated convergence failure, a non-finite state met by the right-hand
/// side) stops the run with stable = false and CVODE's reason. `applied` (dim x nodes, N; empty
/// = none) is added to the loads for the whole run, as the other integrators add
/// State::applied each step.
template <int dim>
RunReport simulate_cvode(const Model<dim>& model, const CvodeOptions& options, Trajectory<dim>& out,
                         bool record_field = false, const Eigen::MatrixXd& applied = {});

/// The right-hand side g(t, y) that CVODE integrates, y = [u_free; v_free] (free nodes in
/// order, node-major), and the analytic Jacobian dg/dy that CVODE's Newton iteration uses, as
/// dense matrices: CVODE converges with a wrong Jacobian, so only a direct check of it (against
/// differences of g) can find one.
template <int dim>
Eigen::VectorXd cvode_rhs(const Model<dim>& model, double t, const Eigen::VectorXd& y,
                          const Eigen::MatrixXd& applied = {});
template <int dim> Eigen::MatrixXd cvode_jacobian(const Model<dim>& model, double t, const Eigen::VectorXd& y);

} // namespace vtb
