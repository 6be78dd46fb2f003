#pragma once
/// \file
/// The reference trajectory of the discrete spring model: SUNDIALS CVODE (BDF, Newton) on
///   u' = v,   M v' = f_int(u, v) + f_ext(t)
/// over the free nodes (supports prescribe u and v inside the right-hand side), with the
/// analytic sparse Jacobian [[0, I], [M^-1 K, M^-1 C]] (K the exact spring Jacobian, C the
/// dashpots', the dependence of the dashpot direction on x omitted) solved by KLU.

#include "vtb/solvers/simulation.hh"

namespace vtb {

struct CvodeOptions {
  double rtol = 1e-8;
  double atol = 1e-12;
  long max_steps = 2'000'000; ///< CVODE steps in the whole run before it gives up
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
