#include "vtb/solvers/cvode_solver.hh"

#include "cvode_newton.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/springs/force_jacobian.hh"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace vtb {
namespace {

using cvode::ReducedNewton;

/// GMRES's Krylov dimension: its preconditioner is Newton's exact inverse for the clamped
/// Jacobian, so one or two iterations reach CVODE's linear tolerance; 5 leaves room where the
/// clamp or the dashpots' omitted terms matter.
constexpr int kKrylovDimension = 5;

/// RAII owner of every SUNDIALS object of one integration (context first, freed last).
class CvodeHandle {
public:
  /// With `krylov`, GMRES (left-preconditioned, no matrix); else KLU on an n x n sparse matrix.
  CvodeHandle(sunindextype n, sunindextype nnz, bool krylov) {
    if (SUNContext_Create(nullptr, &m_ctx) != 0) throw std::runtime_error("cvode: SUNContext_Create failed");
    m_y = N_VNew_Serial(n, m_ctx);
    m_mem = CVodeCreate(CV_BDF, m_ctx);
    if (krylov) {
      m_ls = m_y ? SUNLinSol_SPGMR(m_y, SUN_PREC_LEFT, kKrylovDimension, m_ctx) : nullptr;
    } else {
      m_A = SUNSparseMatrix(n, n, nnz, CSC_MAT, m_ctx);
      m_ls = m_y && m_A ? SUNLinSol_KLU(m_y, m_A, m_ctx) : nullptr;
    }
    if (!m_y || !m_mem || (!krylov && !m_A) || !m_ls) {
      release();
      throw std::runtime_error("cvode: cannot allocate the integrator");
    }
  }
  ~CvodeHandle() { release(); }
  CvodeHandle(const CvodeHandle&) = delete;
  CvodeHandle& operator=(const CvodeHandle&) = delete;

  void* mem() const { return m_mem; }
  N_Vector y() const { return m_y; }
  SUNMatrix matrix() const { return m_A; }
  SUNLinearSolver solver() const { return m_ls; }

private:
  void release() {
    if (m_mem) CVodeFree(&m_mem);
    if (m_ls) SUNLinSolFree(m_ls);
    if (m_A) SUNMatDestroy(m_A);
    if (m_y) N_VDestroy(m_y);
    if (m_ctx) SUNContext_Free(&m_ctx);
    m_mem = nullptr;
    m_ls = nullptr;
    m_A = nullptr;
    m_y = nullptr;
  }
  SUNContext m_ctx = nullptr;
  N_Vector m_y = nullptr;
  void* m_mem = nullptr;
  SUNMatrix m_A = nullptr;
  SUNLinearSolver m_ls = nullptr;
};

/// The ODE of the free nodes: state y = [u_free (dim nf); v_free (dim nf)].
template <int dim> class SpringOde {
public:
  explicit SpringOde(const Model<dim>& model, const Eigen::MatrixXd& applied = {})
      : m_model(model), m_applied(applied), m_nf(static_cast<int>(model.free_nodes.size())),
        m_u(dim, model.num_nodes()), m_v(dim, model.num_nodes()), m_f(dim, model.num_nodes()),
        m_ext(dim, model.num_nodes()) {
    // Jacobian pattern: neighbours (and self) among free nodes, per free node.
    const auto& net = model.net;
    m_nb.resize(static_cast<std::size_t>(m_nf));
    for (int a = 0; a < m_nf; ++a) {
      const int i = model.free_nodes[static_cast<std::size_t>(a)];
      m_nb[static_cast<std::size_t>(a)].push_back(a);
      for (int p = net.adj_ptr[static_cast<std::size_t>(i)]; p < net.adj_ptr[static_cast<std::size_t>(i) + 1]; ++p) {
        const int b = model.free_index[static_cast<std::size_t>(net.adj_node[static_cast<std::size_t>(p)])];
        if (b >= 0) m_nb[static_cast<std::size_t>(a)].push_back(b);
      }
      std::sort(m_nb[static_cast<std::size_t>(a)].begin(), m_nb[static_cast<std::size_t>(a)].end());
    }
    const int N = dim * m_nf;
    m_colptr.assign(static_cast<std::size_t>(2 * N + 1), 0);
    for (int part = 0; part < 2; ++part)
      for (int b = 0; b < m_nf; ++b)
        for (int q = 0; q < dim; ++q) {
          const int col = part * N + b * dim + q;
          m_colptr[static_cast<std::size_t>(col) + 1] =
              m_colptr[static_cast<std::size_t>(col)] + part +
              static_cast<int>(m_nb[static_cast<std::size_t>(b)].size()) * dim;
        }
  }

  sunindextype size() const { return 2 * dim * m_nf; }
  sunindextype nonzeros() const { return m_colptr.back(); }

  /// Full-node state from y at time t (supports prescribed).
  void unpack(double t, const double* y) {
    const int N = dim * m_nf;
    for (int a = 0; a < m_nf; ++a) {
      const int i = m_model.free_nodes[static_cast<std::size_t>(a)];
      for (int p = 0; p < dim; ++p) {
        m_u(p, i) = y[a * dim + p];
        m_v(p, i) = y[N + a * dim + p];
      }
    }
    m_model.apply_constraints(t, m_u, m_v);
  }

  int rhs(double t, const double* y, double* ydot) {
    const int N = dim * m_nf;
    for (int k = 0; k < 2 * N; ++k)
      if (!std::isfinite(y[k])) return 1; // recoverable: CVODE retries with a smaller step
    unpack(t, y);
    m_model.external_forces(t, m_f);
    if (m_applied.cols() == m_f.cols() && m_applied.rows() == dim) m_f += m_applied;
    add_internal_forces(m_model.net, m_u, m_v, m_f);
    for (int a = 0; a < m_nf; ++a) {
      const int i = m_model.free_nodes[static_cast<std::size_t>(a)];
      for (int p = 0; p < dim; ++p) {
        ydot[a * dim + p] = y[N + a * dim + p];
        ydot[N + a * dim + p] = m_f(p, i) / m_model.net.mass[i];
      }
    }
    return 0;
  }

  int jacobian(double t, const double* y, SUNMatrix J) {
    unpack(t, y);
    const int N = dim * m_nf;
    sunindextype* colptr = SUNSparseMatrix_IndexPointers(J);
    sunindextype* rowval = SUNSparseMatrix_IndexValues(J);
    double* data = SUNSparseMatrix_Data(J);
    for (std::size_t c = 0; c < m_colptr.size(); ++c) colptr[c] = m_colptr[c];
    // Row indices and zero values.
    for (int part = 0; part < 2; ++part)
      for (int b = 0; b < m_nf; ++b)
        for (int q = 0; q < dim; ++q) {
          sunindextype pos = m_colptr[static_cast<std::size_t>(part * N + b * dim + q)];
          if (part == 1) {
            rowval[pos] = b * dim + q; // d(u')/dv = I
            data[pos++] = 1.0;
          }
          for (int a : m_nb[static_cast<std::size_t>(b)])
            for (int p = 0; p < dim; ++p) {
              rowval[pos] = N + a * dim + p;
              data[pos++] = 0.0;
            }
        }
    const auto& net = m_model.net;
    auto add = [&](int part, int a, int b, const Mat<dim>& block, double scale) {
      // Entry d(v'_a)/d(x_b) += scale * block / m_a, in column (part, b, q).
      const auto& nb = m_nb[static_cast<std::size_t>(b)];
      const int slot = static_cast<int>(std::lower_bound(nb.begin(), nb.end(), a) - nb.begin());
      const double inv_m = 1.0 / net.mass[m_model.free_nodes[static_cast<std::size_t>(a)]];
      for (int q = 0; q < dim; ++q) {
        const sunindextype base = m_colptr[static_cast<std::size_t>(part * N + b * dim + q)] + part + slot * dim;
        for (int p = 0; p < dim; ++p) data[base + p] += scale * block(p, q) * inv_m;
      }
    };
    // The shared assembly's blocks: d(v'_a)/du_b = sign K_s / m_a, d(v'_a)/dv_b = sign D_s / m_a.
    for_each_jacobian_block(net, m_u, false, [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
      const int a = m_model.free_index[static_cast<std::size_t>(i)],
                b = m_model.free_index[static_cast<std::size_t>(j)];
      if (a < 0 || b < 0) return;
      add(0, a, b, K, sign);
      add(1, a, b, D, sign);
    });
    for_each_cell_block(net.volume, net.rest, m_u, false,
                        [&](int c, int la, int lb, const Mat<dim>& K, const Mat<dim>& D) {
                          const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
                          const int a = m_model.free_index[static_cast<std::size_t>(cell[la])],
                                    b = m_model.free_index[static_cast<std::size_t>(cell[lb])];
                          if (a < 0 || b < 0) return;
                          add(0, a, b, K, 1.0);
                          add(1, a, b, D, 1.0);
                        });
    if (net.mass_damping != 0)
      for (int a = 0; a < m_nf; ++a)
        add(1, a, a,
            -net.mass_damping * net.mass[m_model.free_nodes[static_cast<std::size_t>(a)]] * Mat<dim>::Identity(), 1.0);
    return 0;
  }

  /// CVODE's preconditioner setup: Newton's reduced matrix at y (or at the last Jacobian's
  /// state when `jok`), for gamma.
  int precondition_setup(double t, const double* y, bool jok, int* jcur, double gamma) {
    if (!m_newton) m_newton = std::make_unique<ReducedNewton<dim>>(m_model);
    if (!jok) unpack(t, y);
    *jcur = jok ? 0 : 1;
    return m_newton->setup(m_u, !jok, gamma) ? 0 : 1; // > 0: recoverable (a smaller step)
  }
  int precondition_solve(const double* r, double* z) {
    m_newton->solve(r, z);
    return 0;
  }

  const Nodal<dim>& u() const { return m_u; }
  const Nodal<dim>& v() const { return m_v; }

private:
  const Model<dim>& m_model;
  Eigen::MatrixXd m_applied; ///< constant applied forces (empty: none)
  int m_nf;
  Nodal<dim> m_u, m_v, m_f, m_ext;
  std::vector<std::vector<int>> m_nb;
  std::vector<sunindextype> m_colptr;
  std::unique_ptr<ReducedNewton<dim>> m_newton; ///< GMRES's preconditioner (built at its first setup)
};

template <int dim> int rhs_fn(realtype t, N_Vector y, N_Vector ydot, void* user) {
  return static_cast<SpringOde<dim>*>(user)->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
}

template <int dim> int jac_fn(realtype t, N_Vector y, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
  return static_cast<SpringOde<dim>*>(user)->jacobian(t, N_VGetArrayPointer(y), J);
}

template <int dim>
int psetup_fn(realtype t, N_Vector y, N_Vector, booleantype jok, booleantype* jcur, realtype gamma, void* user) {
  int current = 0;
  const int flag =
      static_cast<SpringOde<dim>*>(user)->precondition_setup(t, N_VGetArrayPointer(y), jok != 0, &current, gamma);
  *jcur = current ? SUNTRUE : SUNFALSE;
  return flag;
}

template <int dim>
int psolve_fn(realtype, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype, realtype, int, void* user) {
  return static_cast<SpringOde<dim>*>(user)->precondition_solve(N_VGetArrayPointer(r), N_VGetArrayPointer(z));
}

/// Whether Newton's systems go to GMRES (else KLU): CvodeOptions::linear_solver.
bool krylov(const CvodeOptions& o, int dim) {
  if (o.linear_solver == "gmres") return true;
  if (o.linear_solver == "klu") return false;
  if (o.linear_solver == "auto") return dim == 3;
  throw std::invalid_argument("cvode: linear_solver must be auto, klu or gmres, not \"" + o.linear_solver + "\"");
}

} // namespace

/// CVODE's initial state: zero displacement, the scene's initial velocity, on the free nodes.
template <int dim> void initial_y(const Model<dim>& model, double* y) {
  const State<dim> s0 = initial_state(model);
  const int N = dim * static_cast<int>(model.free_nodes.size());
  for (std::size_t a = 0; a < model.free_nodes.size(); ++a)
    for (int p = 0; p < dim; ++p) {
      y[static_cast<int>(a) * dim + p] = 0.0;
      y[N + static_cast<int>(a) * dim + p] = s0.v(p, model.free_nodes[a]);
    }
}

/// CVODE set up on the ODE: BDF with the KLU linear solver, the analytic Jacobian, the
/// tolerances, the step budget, and a stop at the duration.
template <int dim> void configure(const CvodeHandle& h, SpringOde<dim>& ode, const CvodeOptions& o, double duration) {
  const auto check = [](int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("cvode: ") + what + " failed: " + CVodeGetReturnFlagName(flag));
  };
  check(CVodeInit(h.mem(), rhs_fn<dim>, 0.0, h.y()), "CVodeInit");
  check(CVodeSStolerances(h.mem(), o.rtol, o.atol), "CVodeSStolerances");
  check(CVodeSetUserData(h.mem(), &ode), "CVodeSetUserData");
  check(CVodeSetLinearSolver(h.mem(), h.solver(), h.matrix()), "CVodeSetLinearSolver");
  if (h.matrix())
    check(CVodeSetJacFn(h.mem(), jac_fn<dim>), "CVodeSetJacFn");
  else
    check(CVodeSetPreconditioner(h.mem(), psetup_fn<dim>, psolve_fn<dim>), "CVodeSetPreconditioner");
  check(CVodeSetMaxNumSteps(h.mem(), o.max_steps), "CVodeSetMaxNumSteps");
  check(CVodeSetStopTime(h.mem(), duration), "CVodeSetStopTime");
}

/// CVODE's counters into the report: steps (and their mean as `dt`), Newton iterations,
/// Jacobian evaluations, error-test and convergence failures.
void report_statistics(void* mem, const CvodeOptions& o, double duration, double total, std::vector<double> per_step,
                       RunReport& rep) {
  long nst = 0, nni = 0, nje = 0, netf = 0, nncf = 0;
  CVodeGetNumSteps(mem, &nst);
  CVodeGetNumNonlinSolvIters(mem, &nni);
  CVodeGetNumJacEvals(mem, &nje);
  CVodeGetNumErrTestFails(mem, &netf);
  CVodeGetNumNonlinSolvConvFails(mem, &nncf);
  rep.steps = rep.steps_taken = nst;
  rep.dt = nst > 0 ? duration / static_cast<double>(nst) : 0.0; // mean step
  rep.step_seconds = step_stats(std::move(per_step));
  rep.step_seconds.mean = nst > 0 ? total / static_cast<double>(nst) : 0.0;
  rep.extra = {
      {"rtol", o.rtol},
      {"atol", o.atol},
      {"cvode_steps", static_cast<double>(nst)},
      {"newton_iterations", static_cast<double>(nni)},
      {"jacobian_evaluations", static_cast<double>(nje)},
      {"error_test_failures", static_cast<double>(netf)},
      {"nonlinear_convergence_failures", static_cast<double>(nncf)},
  };
  long npe = 0, nli = 0;
  if (CVodeGetNumPrecEvals(mem, &npe) == CV_SUCCESS && npe > 0) { // GMRES: its iterations, the factors
    CVodeGetNumLinIters(mem, &nli);
    rep.extra.emplace_back("preconditioner_factors", static_cast<double>(npe));
    rep.extra.emplace_back("linear_iterations", static_cast<double>(nli));
  }
}

template <int dim>
RunReport simulate_cvode(const Model<dim>& model, const CvodeOptions& o, Trajectory<dim>& traj, bool record_field,
                         const Eigen::MatrixXd& applied) {
  using clock = std::chrono::steady_clock;
  RunReport rep = spring_report(model, solvers::kCvode);
  if (!(o.rtol > 0) || !(o.atol > 0)) throw InputError("[solver].rtol and atol must be > 0");

  const auto t0 = clock::now();
  SpringOde<dim> ode(model, applied);
  CvodeHandle h(ode.size(), ode.nonzeros(), krylov(o, dim));
  initial_y(model, N_VGetArrayPointer(h.y()));
  double* y = N_VGetArrayPointer(h.y());
  configure(h, ode, o, model.duration);
  rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();

  const std::vector<double> times = sample_times(model.duration, model.output_interval);
  const long samples = static_cast<long>(times.size());
  std::vector<double> per_step; // wall time per CVODE step, per output interval
  long last_steps = 0;
  auto record = [&](double t) {
    ode.unpack(t, y);
    State<dim> s;
    s.t = t;
    s.u = ode.u();
    s.v = ode.v();
    record_sample(model, s, traj, record_field, rep);
  };
  record(0.0);
  const auto start = clock::now();
  for (long k = 1; k < samples; ++k) {
    const double tout = times[static_cast<std::size_t>(k)];
    double t = 0;
    const auto a = clock::now();
    const int flag = CVode(h.mem(), tout, h.y(), &t, CV_NORMAL);
    const double wall = std::chrono::duration<double>(clock::now() - a).count();
    long nst = 0;
    CVodeGetNumSteps(h.mem(), &nst);
    if (nst > last_steps) per_step.push_back(wall / static_cast<double>(nst - last_steps));
    last_steps = nst;
    if (flag < 0) {
      rep.stable = false;
      rep.failure = std::string("CVODE: ") + CVodeGetReturnFlagName(flag);
      rep.failure_time = t;
      break;
    }
    record(t);
  }
  const double total = std::chrono::duration<double>(clock::now() - start).count();
  report_statistics(h.mem(), o, model.duration, total, std::move(per_step), rep);
  rep.total_seconds = total;
  return rep;
}

template <int dim>
Eigen::VectorXd cvode_rhs(const Model<dim>& model, double t, const Eigen::VectorXd& y, const Eigen::MatrixXd& applied) {
  SpringOde<dim> ode(model, applied);
  if (y.size() != ode.size()) throw std::invalid_argument("cvode_rhs: y has the wrong size");
  Eigen::VectorXd g(ode.size());
  if (ode.rhs(t, y.data(), g.data()) != 0) g.setConstant(std::numeric_limits<double>::quiet_NaN());
  return g;
}

template <int dim> Eigen::MatrixXd cvode_jacobian(const Model<dim>& model, double t, const Eigen::VectorXd& y) {
  SpringOde<dim> ode(model);
  if (y.size() != ode.size()) throw std::invalid_argument("cvode_jacobian: y has the wrong size");
  SUNContext ctx = nullptr;
  if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("cvode: SUNContext_Create failed");
  SUNMatrix J = SUNSparseMatrix(ode.size(), ode.size(), ode.nonzeros(), CSC_MAT, ctx);
  ode.jacobian(t, y.data(), J);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(ode.size(), ode.size());
  const sunindextype* colptr = SUNSparseMatrix_IndexPointers(J);
  const sunindextype* rowval = SUNSparseMatrix_IndexValues(J);
  const double* data = SUNSparseMatrix_Data(J);
  for (sunindextype c = 0; c < ode.size(); ++c)
    for (sunindextype k = colptr[c]; k < colptr[c + 1]; ++k) dense(rowval[k], c) += data[k];
  SUNMatDestroy(J);
  SUNContext_Free(&ctx);
  return dense;
}

template Eigen::VectorXd cvode_rhs<2>(const Model<2>&, double, const Eigen::VectorXd&, const Eigen::MatrixXd&);
template Eigen::VectorXd cvode_rhs<3>(const Model<3>&, double, const Eigen::VectorXd&, const Eigen::MatrixXd&);
template Eigen::MatrixXd cvode_jacobian<2>(const Model<2>&, double, const Eigen::VectorXd&);
template Eigen::MatrixXd cvode_jacobian<3>(const Model<3>&, double, const Eigen::VectorXd&);

template RunReport simulate_cvode<2>(const Model<2>&, const CvodeOptions&, Trajectory<2>&, bool,
                                     const Eigen::MatrixXd&);
template RunReport simulate_cvode<3>(const Model<3>&, const CvodeOptions&, Trajectory<3>&, bool,
                                     const Eigen::MatrixXd&);

} // namespace vtb
