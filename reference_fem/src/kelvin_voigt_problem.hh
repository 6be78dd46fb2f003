#pragma once
// Internal to reference_fem: the Kelvin-Voigt finite element reference, written once for the
// serial and the distributed backends (backends.hh), in the style of the deal.II tutorials
// (step-8, step-18, step-23, step-40): setup / assemble / solve_step / record, and run().
// This header declares the class; its members are defined by job in kelvin_voigt_setup.cc
// (run, dofs, supports, assembly), kelvin_voigt_step.cc (loads, initial state, the linear and
// the Newton step) and kelvin_voigt_record.cc (probes, reactions, strain, frames), each
// instantiated for both backends in 2D and 3D.
//
// The semi-discrete problem is  M a + C v + K u = f(t),  with K the linear elasticity
// stiffness (plane stress with thickness t in 2D: K and M carry t, the loads are total forces,
// so a 2D displacement scales as 1/t), M the consistent mass, and the Voigt damping
// C = tau K + gamma M (sigma = C : (eps + tau eps_dot), mass damping gamma).
// Every time scheme solves for the new displacement with one constant matrix (time_scheme.hh):
//   backward Euler:  (M / dt^2 + C / dt + K) u+ = f+ + M (u / dt^2 + v / dt) + C u / dt
//   Newmark family with generalized-alpha weights (Chung and Hulbert 1993):
//     (1 - am) M a+ + am M a + (1 - af) (C v+ + K u+) + af (C v + K u) = f(t + (1 - af) dt),
//     u+ = u + dt v + dt^2 ((1/2 - beta) a + beta a+),  v+ = v + dt ((1 - gamma) a + gamma a+),
//   so that a+ = c1 u+ + d_a, v+ = c2 u+ + d_v with c1 = 1 / (beta dt^2), c2 = gamma / (beta dt),
//   and ((1 - am) c1 M + (1 - af) c2 C + (1 - af) K) u+ = the rest.
//   `newmark` is average acceleration (am = af = 0, beta = 1/4, gamma = 1/2: second order,
//   no numerical damping); `generalized-alpha` uses rho_inf = 0 (asymptotic annihilation:
//   second order, removes the highest modes, which a step load or a kink of a drive excites and
//   average acceleration keeps ringing: on the 123-node plate its clamp reaction lagged the
//   step load by 0.2 s; with rho_inf = 0.8 it still lagged 0.1 s, with 0 it is right after one
//   step).
// Prescribed displacements (fixes, drives) are imposed by lifting: u+ = u_bar + delta, with
// u_bar holding the prescribed values, and A0 delta = b - A u_bar, where A0 is A with the
// constrained rows and columns eliminated (a positive diagonal left), factorised once.
// Per-dof data (support point, component, support) is held for every dof this process sees
// (the dofs of its own cells; all dofs in a serial run); nodal outputs are summed over ranks.
#include "vtb/fem/kelvin_voigt.hh"

#include "amg_krylov.hh"
#include "backends.hh"
#include "grid.hh"
#include "nonlinear.hh"
#include "time_loop.hh"
#include "time_scheme.hh"

#include <deal.II/base/timer.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/lac/affine_constraints.h>

#include <Eigen/Core>

#include <sstream>

namespace vtb::fem {

template <int dim, class Backend> class KelvinVoigtProblem {
  using Vector = typename Backend::Vector;
  using Matrix = typename Backend::Matrix;
  using dof_t = dealii::types::global_dof_index;
  static constexpr dof_t kUnseen = dealii::numbers::invalid_dof_index;

public:
  KelvinVoigtProblem(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options, MPI_Comm comm)
      : m_model(model), m_mat(material), m_opt(options),
        m_scheme(options.scheme, options.static_solve, options.dt, options.static_path), m_backend(comm),
        m_tria(Backend::make_tria(comm)), m_fe(dealii::FE_SimplexP<dim>(options.degree), dim),
        m_mapping(dealii::FE_SimplexP<dim>(1)), m_dofs(*m_tria),
        m_timer(m_timer_stream, dealii::TimerOutput::never, dealii::TimerOutput::wall_times) {}

  RunReport run(Trajectory<dim>& out, bool record_field);

  /// Static answers (the options' static solve) at the scene's nodes, one column per column of
  /// `g`: the body force per unit mass whose nodal values (node v, component i) -> dim v + i
  /// are g's, linear over each of the scene's cells (a P1 field, exact on every refinement),
  /// with the supports held at zero. Serial backend only (kelvin_voigt_answers.cc).
  Eigen::MatrixXd body_force_answers(const Eigen::MatrixXd& g);

  /// Nested iteration (docs/fem.md): a static nonlinear solve starts Newton at the whole load
  /// from `coarse`, the answer of the level one uniform refinement below (P2), and falls back
  /// to the load continuation from rest where Newton does not converge from it. Before run().
  void start_from(const LevelAnswer<dim>* coarse) { m_start = coarse; }
  /// After run(): the displacement at every support point, on every rank (the next level's start).
  LevelAnswer<dim> answer(double tolerance, MPI_Comm comm);

private:
  RunReport header() const;

  /// Dofs, the matrices' pattern, the vectors, and each seen dof's support point and component.
  void setup_dofs();

  /// The dofs of the scene's nodes (the original nodes stay support points under refinement
  /// and for P2); every node must be found on some rank.
  void setup_nodes();

  /// Which dofs each support prescribes: for a box, the support points inside it; for a group,
  /// the support points on its facets and its nodes; for a point, the dofs of its node.
  void setup_constraints();

  /// K, M, C = tau K + gamma M and the scheme's A = ck K + cm M + cc C, by quadrature of degree
  /// 2p (exact on affine simplices); A0 and M0 with the prescribed rows and columns eliminated.
  /// Only the matrices the run reads (matrices_read) are allocated and assembled.
  void assemble();

  /// The matrices this run reads (docs/fem.md, "What a run assembles"): a linear static solve
  /// K (its reactions and A = K u) and A0; a nonlinear static solve only the tangent T; the
  /// static answers to body forces K, M and A0; a transient all of them.
  std::vector<Matrix*> matrices_read();

  /// Direct or iterative (FemOptions::linear_solver; auto: iterative_by_default), and the AMG's
  /// near-null space, the rigid-body modes at the support points.
  void choose_solvers();
  /// The solver's name and its work for the report (linear_solver, krylov_*, amg_setups).
  void report_solvers(RunReport& rep) const;

  double prescribed(dof_t d, double t) const {
    const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of[d])];
    return s.driven ? ramp_factor(t, s.start, s.ramp) * s.displacement[m_comp[d]] : 0.0;
  }
  double prescribed_rate(dof_t d, double t) const {
    const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of[d])];
    return s.driven ? ramp_rate(t, s.start, s.ramp) * s.displacement[m_comp[d]] : 0.0;
  }

  /// f(t): uniform tractions total / |region| integrated over the load facets, and point loads
  /// on their node's dofs.
  void load_vector(double t, Vector& f);

  /// Adds the integral of each boundary id's traction (a total force over the facets' length
  /// or area: no thickness factor, the load is the total force on the 2D body).
  void add_tractions(const std::vector<dealii::Tensor<1, dim>>& traction, Vector& f);

  void zero_prescribed(Vector& v);

  /// u = the prescribed values at t = 0; v = the initial velocity. The problem holds the
  /// initial velocity v(x) = v_lin + w x (x - c) at the mesh's nodes; that field is affine, so
  /// interpolating it at the support points is exact: the affine fit through the nodes.
  /// Newmark needs a(0) = M^-1 (f(0-) - C v - K u) on the free dofs: the loads as they are just
  /// before t = 0, since a step at t = 0 acts from the first step on (its instantaneous
  /// acceleration M^-1 F is an impulse a one-step scheme cannot represent; taken as a(0) it
  /// throws the first steps of Newmark and generalized-alpha far off the solution).
  void initial_state();

  /// One step to t_new: u+ from A u+ = b with the prescribed values lifted, then v+ and a+.
  void step(double t_new);

  /// The nonlinear solid's internal force f_int(u, v) into f and, with `tangent`, its tangent
  /// into m_T (nonlinear.hh; constrained rows and columns eliminated).
  void nonlinear_force(const Vector& u, const Vector& v, Vector& f, double rate, bool tangent);
  /// smallest_volume_ratio (nonlinear.hh) of u over every rank's cells.
  double volume_ratio(const Vector& u);

  /// Newton on the residual of the step, from m_ubar (prescribed values in place):
  ///   backward Euler: M (v+ - v) / dt + gamma M v+ + f_int(u+, v+) - f = 0, v+ = (u+ - u) / dt;
  ///   static: f_int(u+, 0) - load_scale f = 0.
  /// Converged when the free dofs' residual is 1e-9 of its first value (or of the load), or the
  /// update 1e-10 of the displacement; false when neither within 25 iterations (30 in a static
  /// increment), or non-finite. A correction that inverts a quadrature point (det F <= 0, or a
  /// non-finite residual) is halved, up to 10 times. `max_iterations` > 0 replaces 25 / 30.
  bool newton(double load_scale, int max_iterations = 0);
  /// Newton's residual at m_ubar into r (the step's, as newton describes), zero on the
  /// prescribed dofs; with `tangent`, its tangent into m_T.
  void residual(double load_scale, Vector& r, bool tangent);
  /// Shortens Newton's last correction where it overshoots (newton, from m_ubar = u0 - m_delta,
  /// g0 = m_delta . R(u0)); residuals alone, no tangent (kelvin_voigt_step.cc).
  void line_search(double load_scale, double g0);
  /// The line search starts where G(1) < -kOvershootRatio G(0) and ends at |G(eta)| <=
  /// kLineSearchRatio G(0), or after kLineSearchTrials residuals.
  static constexpr double kLineSearchRatio = 0.5, kOvershootRatio = 1.0;
  static constexpr int kLineSearchTrials = 4;
  /// Newton's iterations from the coarser level's answer (nested iteration) before the solve
  /// falls back to the continuation from rest: from the exact coarse field (LevelAnswer) with the
  /// line search Newton converged in 8 on the test press (serially and under np 2) and in 4 on
  /// a cantilever; where it stalls (a graded press refined once, docs/fem.md) more only cost.
  static constexpr int kNestedIterations = 12;
  /// The iterative corrections' forcing terms (newton): the first, the largest, and the finest.
  static constexpr double kFirstForcing = 1e-2, kFinestForcing = 1e-8;
  /// Newton's work over the run, for summary.json (report_solvers).
  struct NewtonStats {
    long iterations = 0, backtracks = 0, increments = 0, cuts = 0, line_searches = 0;
  };
  NewtonStats m_newton_stats;
  /// The smallest det F over the quadrature points: of the last assembly (nonlinear_force),
  /// and of every equilibrium Newton accepted (summary.json's min_volume_ratio).
  double m_min_J = 1, m_min_J_accepted = std::numeric_limits<double>::infinity();

  /// The nonlinear step: backward Euler with Newton, or the static solve by load continuation
  /// (the loads and prescribed values scaled from 0 to 1 in increments that grow after a
  /// converged solve and halve after a failed one).
  void step_nonlinear(double t_new);
  /// m_ubar from m_start (LevelAnswer's rule); false where a fine vertex has no coarse value.
  bool guess_from_coarse();
  const LevelAnswer<dim>* m_start = nullptr;
  bool m_nested_converged = false; ///< Newton converged from the coarse level's answer

  /// Stops a nonlinear run as unstable (run() reports why and when): the state turns
  /// non-finite, which the time loop's check catches.
  void fail_nonlinear(const std::string& why, double t);

  /// Probes, reactions (from the residual R = M a + C v + K u - f at the constrained dofs: the
  /// force each support exerts on the body) and the nodal field, summed over the ranks (each
  /// owns its dofs); the largest principal strain at the cell centres, max over the ranks.
  void record(double t, Trajectory<dim>& out, bool record_field);

  /// The samples within the last step (time_loop.hh), and their frames, blended like the
  /// samples from the FE fields at the step's ends.
  void interpolate_samples(Trajectory<dim>& out, std::span<const double> times);

  /// The displacement on the (refined, possibly P2) FE mesh, as deal.II writes it (one
  /// process: run_scene refuses frames under MPI).
  void write_frame(const Vector& u, std::size_t index);

  const Problem<dim>& m_model;
  const MaterialDesc& m_mat;
  const FemOptions m_opt;
  const TimeScheme m_scheme;
  Backend m_backend;
  std::unique_ptr<typename Backend::Tria> m_tria;
  dealii::FESystem<dim> m_fe;
  dealii::MappingFE<dim> m_mapping;
  dealii::DoFHandler<dim> m_dofs;
  dealii::IndexSet m_owned, m_relevant;
  std::vector<std::vector<int>> m_loads_of_id; ///< boundary id -> the loads on its facets (id 0: none)
  std::vector<dealii::Point<dim>> m_point;     ///< per dof: support point (seen dofs)
  std::vector<int> m_comp;                     ///< per dof: component, -1 if not seen here
  std::vector<int> m_support_of;               ///< per dof: support index or -1
  std::vector<dof_t> m_node;                   ///< [node * dim + component], kUnseen if not seen here
  dealii::AffineConstraints<double> m_constraints;
  Matrix m_K, m_M, m_C, m_A, m_A0, m_M0, m_T; ///< m_T: the nonlinear tangent
  /// The linear step's A0 (symmetric positive definite) and the nonlinear tangent.
  ChosenSolver<typename Backend::SpdSolver, Matrix, Vector> m_solver;
  ChosenSolver<typename Backend::Solver, Matrix, Vector> m_newton;
  Vector m_u, m_v, m_a, m_f, m_rhs, m_tmp, m_ubar, m_delta, m_da, m_dv, m_trial;
  Vector m_ghosted, m_ghosted_v, m_frame_prev, m_frame_last, m_frame_mix;
  double m_max_strain = 0, m_max_rotation = 0;
  std::string m_nonlinear_failure; ///< why a nonlinear run stopped, empty while it runs
  double m_failure_time = -1;
  double m_static_time = -1; ///< the time of the last static equilibrium (a static path), -1 before the first
  bool m_answers = false;    ///< body_force_answers' set-up (its matrices: matrices_read)
  std::ostringstream m_timer_stream;
  dealii::TimerOutput m_timer;
};

} // namespace vtb::fem
