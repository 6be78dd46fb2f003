#pragma once
// Internal to reference_fem: the Kelvin-Voigt finite element reference, written once for the
// serial and the distributed backends (backends.hh), in the style of the deal.II tutorials
// (step-8, step-18, step-23, step-40): setup / assemble / solve_step / record, and run().
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
#include "vtb/core/cell_fields.hh"
#include "vtb/core/solver_names.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/meshes/atomic_file.hh"

#include "backends.hh"
#include "grid.hh"
#include "nonlinear.hh"
#include "time_loop.hh"
#include "time_scheme.hh"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/timer.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/numerics/data_out.h>

#include <Eigen/Dense>

#include <chrono>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

namespace vtb::fem {

template <int dim, class Backend> class KelvinVoigtProblem {
  using Vector = typename Backend::Vector;
  using Matrix = typename Backend::Matrix;
  using dof_t = dealii::types::global_dof_index;
  static constexpr dof_t kUnseen = dealii::numbers::invalid_dof_index;

public:
  KelvinVoigtProblem(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options, MPI_Comm comm)
      : m_model(model), m_mat(material), m_opt(options), m_scheme(options.scheme, options.static_solve, options.dt),
        m_backend(comm), m_tria(Backend::make_tria(comm)), m_fe(dealii::FE_SimplexP<dim>(options.degree), dim),
        m_mapping(dealii::FE_SimplexP<dim>(1)), m_dofs(*m_tria),
        m_timer(m_timer_stream, dealii::TimerOutput::never, dealii::TimerOutput::wall_times) {}

  RunReport run(Trajectory<dim>& out, bool record_field) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    {
      dealii::TimerOutput::Scope s(m_timer, "setup");
      m_backend.create(m_model, m_opt.refinements, *m_tria, m_loads_of_id);
      setup_dofs();
      setup_nodes();
      setup_constraints();
    }
    {
      dealii::TimerOutput::Scope s(m_timer, "assembly");
      assemble();
    }
    {
      dealii::TimerOutput::Scope s(m_timer, "factorisation");
      m_solver.factor(m_A0);
      initial_state();
    }
    RunReport rep = header();
    rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    march(
        m_scheme, m_model.duration, m_model.output_interval, rep,
        [&](double t) {
          dealii::TimerOutput::Scope s(m_timer, "time stepping");
          step(t);
        },
        [&] { return std::isfinite(m_u.l2_norm()); },
        [&](double t) {
          dealii::TimerOutput::Scope s(m_timer, "output");
          record(t, out, record_field);
        },
        [&](std::span<const double> times) {
          dealii::TimerOutput::Scope s(m_timer, "output");
          interpolate_samples(out, times);
        });
    if (!m_nonlinear_failure.empty()) {
      rep.stable = false;
      rep.failure = m_nonlinear_failure;
      rep.failure_time = m_failure_time;
    }
    rep.max_strain = m_max_strain;
    rep.max_rotation = m_max_rotation;
    for (const auto& [phase, seconds] : m_timer.get_summary_data(dealii::TimerOutput::total_wall_time)) {
      std::string key = "phase_" + phase + "_seconds";
      std::replace(key.begin(), key.end(), ' ', '_');
      rep.extra.push_back({key, seconds});
    }
    return rep;
  }

private:
  RunReport header() const {
    RunReport rep;
    rep.solver = solvers::kFem;
    rep.dim = dim;
    rep.dt = m_opt.dt;
    rep.duration = m_model.duration;
    rep.nodes = m_model.num_nodes();
    rep.extra = {{"cells", static_cast<double>(m_tria->n_global_active_cells())},
                 {"dofs", static_cast<double>(m_dofs.n_dofs())},
                 {"degree", static_cast<double>(m_opt.degree)},
                 {"refinements", static_cast<double>(m_opt.refinements)},
                 {"mpi_ranks", static_cast<double>(m_backend.ranks())}};
    return rep;
  }

  /// Dofs, the matrices' pattern, the vectors, and each seen dof's support point and component.
  void setup_dofs() {
    m_dofs.distribute_dofs(m_fe);
    m_owned = m_dofs.locally_owned_dofs();
    dealii::DoFTools::extract_locally_relevant_dofs(m_dofs, m_relevant);
    dealii::DynamicSparsityPattern dsp(m_relevant);
    dealii::DoFTools::make_sparsity_pattern(m_dofs, dsp, dealii::AffineConstraints<double>(), true);
    m_backend.reinit(dsp, m_owned, m_relevant, {&m_K, &m_M, &m_C, &m_A, &m_A0, &m_M0, &m_T});
    for (auto* v : {&m_u, &m_v, &m_a, &m_f, &m_rhs, &m_tmp, &m_ubar, &m_delta, &m_da, &m_dv})
      m_backend.reinit(*v, m_owned);
    m_backend.reinit_ghosted(m_ghosted, m_owned, m_relevant);
    m_backend.reinit_ghosted(m_ghosted_v, m_owned, m_relevant);

    const auto n = m_dofs.n_dofs();
    m_point.assign(n, dealii::Point<dim>());
    m_comp.assign(n, -1); // -1: not seen by this process
    dealii::FEValues<dim> fev(m_mapping, m_fe, dealii::Quadrature<dim>(m_fe.get_unit_support_points()),
                              dealii::update_quadrature_points);
    std::vector<dof_t> local(m_fe.n_dofs_per_cell());
    for (const auto& cell : m_dofs.active_cell_iterators()) {
      if (!cell->is_locally_owned()) continue;
      fev.reinit(cell);
      cell->get_dof_indices(local);
      for (unsigned int i = 0; i < local.size(); ++i) {
        m_point[local[i]] = fev.quadrature_point(i);
        m_comp[local[i]] = static_cast<int>(m_fe.system_to_component_index(i).first);
      }
    }
  }

  /// The dofs of the scene's nodes (the original nodes stay support points under refinement
  /// and for P2); every node must be found on some rank.
  void setup_nodes() {
    std::map<std::vector<double>, int> node_of_point;
    for (int i = 0; i < m_model.num_nodes(); ++i) {
      const dealii::Point<dim> p = to_point<dim>(m_model.mesh.points.col(i));
      node_of_point[std::vector<double>(p.begin_raw(), p.end_raw())] = i;
    }
    m_node.assign(static_cast<std::size_t>(m_model.num_nodes()) * dim, kUnseen);
    std::vector<double> found(static_cast<std::size_t>(m_model.num_nodes()), 0.0);
    for (dof_t d = 0; d < m_dofs.n_dofs(); ++d) {
      if (m_comp[d] < 0) continue;
      const auto it = node_of_point.find(std::vector<double>(m_point[d].begin_raw(), m_point[d].end_raw()));
      if (it == node_of_point.end()) continue;
      m_node[static_cast<std::size_t>(it->second) * dim + static_cast<std::size_t>(m_comp[d])] = d;
      found[static_cast<std::size_t>(it->second)] = 1;
    }
    m_backend.sum(found);
    for (std::size_t i = 0; i < found.size(); ++i)
      if (found[i] == 0) throw std::runtime_error("fem: node " + std::to_string(i) + " is not a support point");
  }

  /// Which dofs each support prescribes: for a box, the support points inside it; for a group,
  /// the support points on its facets and its nodes; for a point, the dofs of its node.
  void setup_constraints() {
    const auto n = m_dofs.n_dofs();
    m_support_of.assign(n, -1);
    const double grow = 1e-9 * bounding_diagonal(m_model.mesh), tol = 1e-10 * bounding_diagonal(m_model.mesh);
    for (std::size_t s = 0; s < m_model.supports.size(); ++s) {
      const auto& sup = m_model.supports[s];
      for (int node : sup.nodes)
        for (int a = 0; a < dim; ++a) {
          const dof_t d = m_node[static_cast<std::size_t>(node) * dim + static_cast<std::size_t>(a)];
          if (d != kUnseen) m_support_of[d] = static_cast<int>(s);
        }
      for (dof_t d = 0; d < n; ++d) {
        if (m_comp[d] < 0) continue;
        bool in = false;
        if (sup.box) {
          in = true;
          for (int a = 0; a < dim; ++a)
            in = in && m_point[d][a] >= sup.box->min[a] - grow && m_point[d][a] <= sup.box->max[a] + grow;
        }
        for (const auto& f : sup.facets)
          if (!in) in = on_facet<dim>(m_model.mesh, m_point[d], f, tol);
        if (in) m_support_of[d] = static_cast<int>(s);
      }
    }
    m_constraints.reinit(m_relevant);
    for (dof_t d = 0; d < n; ++d)
      if (m_support_of[d] >= 0) m_constraints.add_line(d);
    m_constraints.close();
  }

  /// K, M, C = tau K + gamma M and the scheme's A = ck K + cm M + cc C, by quadrature of degree
  /// 2p (exact on affine simplices); A0 and M0 with the prescribed rows and columns eliminated.
  void assemble() {
    const double ck = m_scheme.ck(), cm = m_scheme.cm(), cc = m_scheme.cc();
    const dealii::QGaussSimplex<dim> quad(static_cast<unsigned int>(m_opt.degree + 1));
    dealii::FEValues<dim> fev(m_mapping, m_fe, quad,
                              dealii::update_values | dealii::update_gradients | dealii::update_JxW_values);
    const unsigned int nd = m_fe.n_dofs_per_cell();
    dealii::FullMatrix<double> k(nd, nd), m(nd, nd), c(nd, nd), a(nd, nd);
    std::vector<dof_t> local(nd);
    const dealii::AffineConstraints<double> none;
    for (const auto& cell : m_dofs.active_cell_iterators()) {
      if (!cell->is_locally_owned()) continue;
      fev.reinit(cell);
      element_matrices(fev, m_fe, m_mat, k, m);
      c = 0;
      c.add(m_mat.retardation_time, k, m_mat.mass_damping, m);
      a = 0;
      a.add(ck, k, cm, m);
      a.add(cc, c);
      cell->get_dof_indices(local);
      none.distribute_local_to_global(k, local, m_K);
      none.distribute_local_to_global(m, local, m_M);
      none.distribute_local_to_global(c, local, m_C);
      none.distribute_local_to_global(a, local, m_A);
      m_constraints.distribute_local_to_global(a, local, m_A0);
      m_constraints.distribute_local_to_global(m, local, m_M0);
    }
    for (auto* A : {&m_K, &m_M, &m_C, &m_A, &m_A0, &m_M0}) A->compress(dealii::VectorOperation::add);
  }

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
  void load_vector(double t, Vector& f) {
    f = 0;
    std::vector<dealii::Tensor<1, dim>> traction(m_loads_of_id.size());
    bool any = false;
    for (std::size_t id = 1; id < m_loads_of_id.size(); ++id)
      for (int l : m_loads_of_id[id]) {
        const auto& load = m_model.loads[static_cast<std::size_t>(l)];
        double measure = 0;
        for (const auto& fc : load.facets) measure += facet_measure(m_model.mesh, fc);
        const double s = ramp_factor(t, load.start, load.ramp);
        for (int a = 0; a < dim; ++a) traction[id][a] += s * load.total[a] / measure;
        any = any || s != 0;
      }
    if (any) add_tractions(traction, f);
    for (const auto& load : m_model.loads) {
      if (!load.facets.empty()) continue;
      const double s = ramp_factor(t, load.start, load.ramp);
      for (std::size_t k = 0; k < load.nodes.size(); ++k)
        for (int a = 0; a < dim; ++a) {
          const dof_t d = m_node[static_cast<std::size_t>(load.nodes[k]) * dim + static_cast<std::size_t>(a)];
          if (d != kUnseen && m_owned.is_element(d)) f[d] += s * load.force(a, static_cast<Eigen::Index>(k));
        }
    }
    f.compress(dealii::VectorOperation::add);
  }

  /// Adds the integral of each boundary id's traction (a total force over the facets' length
  /// or area: no thickness factor, the load is the total force on the 2D body).
  void add_tractions(const std::vector<dealii::Tensor<1, dim>>& traction, Vector& f) {
    const dealii::QGaussSimplex<dim - 1> fquad(static_cast<unsigned int>(m_opt.degree + 1));
    dealii::FEFaceValues<dim> fv(m_mapping, m_fe, fquad, dealii::update_values | dealii::update_JxW_values);
    std::vector<dof_t> local(m_fe.n_dofs_per_cell());
    dealii::Vector<double> cell_f(m_fe.n_dofs_per_cell());
    const dealii::AffineConstraints<double> none;
    for (const auto& cell : m_dofs.active_cell_iterators()) {
      if (!cell->is_locally_owned()) continue;
      cell_f = 0;
      bool on_load = false;
      for (const unsigned int face : cell->face_indices()) {
        const auto id = cell->face(face)->boundary_id();
        if (!cell->face(face)->at_boundary() || id == 0 || id >= m_loads_of_id.size()) continue;
        fv.reinit(cell, face);
        on_load = true;
        for (unsigned int q = 0; q < fquad.size(); ++q)
          for (unsigned int i = 0; i < cell_f.size(); ++i)
            cell_f[i] += traction[id][m_fe.system_to_component_index(i).first] * fv.shape_value(i, q) * fv.JxW(q);
      }
      if (!on_load) continue;
      cell->get_dof_indices(local);
      none.distribute_local_to_global(cell_f, local, f);
    }
  }

  void zero_prescribed(Vector& v) {
    for (const auto d : m_owned)
      if (m_support_of[d] >= 0) v[d] = 0;
    v.compress(dealii::VectorOperation::insert);
  }

  /// u = the prescribed values at t = 0; v = the initial velocity. The problem holds the
  /// initial velocity v(x) = v_lin + w x (x - c) at the mesh's nodes; that field is affine, so
  /// interpolating it at the support points is exact: the affine fit through the nodes.
  /// Newmark needs a(0) = M^-1 (f(0-) - C v - K u) on the free dofs: the loads as they are just
  /// before t = 0, since a step at t = 0 acts from the first step on (its instantaneous
  /// acceleration M^-1 F is an impulse a one-step scheme cannot represent; taken as a(0) it
  /// throws the first steps of Newmark and generalized-alpha far off the solution).
  void initial_state() {
    m_u = 0;
    m_a = 0;
    const Nodal<dim>& V = m_model.initial_velocity;
    Eigen::Matrix<double, dim + 1, Eigen::Dynamic> X(dim + 1, m_model.num_nodes());
    X.topRows(dim) = m_model.mesh.points;
    X.row(dim).setOnes();
    const Eigen::Matrix<double, dim, dim + 1> affine = (X * X.transpose()).ldlt().solve(X * V.transpose()).transpose();
    for (const auto d : m_owned) {
      Eigen::Matrix<double, dim + 1, 1> x;
      for (int a = 0; a < dim; ++a) x[a] = m_point[d][a];
      x[dim] = 1;
      m_v[d] = affine.row(m_comp[d]).dot(x);
      if (m_support_of[d] >= 0) {
        m_u[d] = prescribed(d, 0.0);
        m_v[d] = prescribed_rate(d, 0.0);
      }
    }
    m_u.compress(dealii::VectorOperation::insert);
    m_v.compress(dealii::VectorOperation::insert);
    if (!m_scheme.newmark_family) return;
    load_vector(-1e-12 * m_opt.dt, m_rhs);
    m_C.vmult(m_tmp, m_v);
    m_rhs -= m_tmp;
    m_K.vmult(m_tmp, m_u);
    m_rhs -= m_tmp;
    zero_prescribed(m_rhs);
    typename Backend::Solver mass;
    mass.factor(m_M0);
    mass.solve(m_a, m_rhs);
  }

  /// One step to t_new: u+ from A u+ = b with the prescribed values lifted, then v+ and a+.
  void step(double t_new) {
    if (m_opt.nonlinear) return step_nonlinear(t_new);
    load_vector(m_scheme.load_time(t_new), m_rhs);
    m_scheme.add_history(m_M, m_C, m_K, m_u, m_v, m_a, m_da, m_dv, m_tmp, m_rhs);
    m_ubar = m_u;
    for (const auto d : m_owned)
      if (m_support_of[d] >= 0) m_ubar[d] = prescribed(d, t_new);
    m_ubar.compress(dealii::VectorOperation::insert);
    m_A.vmult(m_tmp, m_ubar);
    m_rhs -= m_tmp;
    zero_prescribed(m_rhs);
    m_solver.solve(m_delta, m_rhs);
    m_ubar += m_delta;
    if (!m_opt.static_solve) {
      for (const auto d : m_owned) {
        if (m_scheme.newmark_family && m_support_of[d] >= 0) {
          // On prescribed dofs the motion is known: its rate and (piecewise linear ramps) zero
          // acceleration; the Newmark update would ring there after a kink.
          m_v[d] = prescribed_rate(d, t_new);
          m_a[d] = 0;
          continue;
        }
        double v = m_v[d], a = m_a[d];
        m_scheme.update(m_ubar[d], m_u[d], m_da[d], m_dv[d], v, a);
        m_v[d] = v;
        m_a[d] = a;
      }
      m_a.compress(dealii::VectorOperation::insert);
      m_v.compress(dealii::VectorOperation::insert);
    }
    m_u = m_ubar;
  }

  /// The nonlinear solid's internal force f_int(u, v) into f and, with `tangent`, its tangent
  /// into m_T (nonlinear.hh; constrained rows and columns eliminated).
  void nonlinear_force(const Vector& u, const Vector& v, Vector& f, double rate, bool tangent) {
    m_ghosted = u;
    m_ghosted_v = v;
    f = 0;
    if (tangent) m_T = 0;
    assemble_nonlinear<dim>(m_mapping, m_fe, m_dofs, m_mat, m_opt.degree, m_ghosted, m_ghosted_v, m_constraints,
                            NonlinearTargets<dim, Vector, Matrix>{&f, tangent ? &m_T : nullptr, rate});
  }

  /// Newton on the residual of the step, from m_ubar (prescribed values in place):
  ///   backward Euler: M (v+ - v) / dt + gamma M v+ + f_int(u+, v+) - f = 0, v+ = (u+ - u) / dt;
  ///   static: f_int(u+, 0) - load_scale f = 0.
  /// Converged when the free dofs' residual is 1e-9 of its first value (or of the load), or the
  /// update 1e-10 of the displacement; false when neither within 25 iterations, or non-finite.
  bool newton(double load_scale) {
    const bool dynamic = !m_opt.static_solve;
    const double dt = m_opt.dt, rate = dynamic ? 1 / dt : 0.0;
    const double mass_weight = dynamic ? 1 / (dt * dt) + m_mat.mass_damping / dt : 0.0;
    double first = -1;
    for (int it = 0; it < 25; ++it) {
      m_dv = m_ubar;
      m_dv -= m_u;
      m_dv *= rate;
      nonlinear_force(m_ubar, m_dv, m_rhs, rate, true);
      if (dynamic) m_T.add(mass_weight, m_M0); // the consistent mass, prescribed rows eliminated
      m_rhs.add(-load_scale, m_f);
      if (dynamic) {
        m_tmp = m_dv;
        m_tmp -= m_v;
        m_tmp *= 1 / dt;
        m_tmp.add(m_mat.mass_damping, m_dv);
        m_M.vmult_add(m_rhs, m_tmp);
      }
      zero_prescribed(m_rhs);
      const double r = m_rhs.l2_norm();
      if (!std::isfinite(r)) return false;
      if (first < 0) first = std::max(r, load_scale * m_f.l2_norm());
      if (r <= 1e-9 * first) return true;
      m_newton.factor(m_T);
      m_newton.solve(m_delta, m_rhs);
      m_ubar -= m_delta;
      // Round-off bounds the residual at about cond(K) 1e-16 of the load (6e-7 of it on a thin
      // cantilever, cond ~ 1e9): an update of 1e-10 of the displacement has converged too.
      if (m_delta.l2_norm() <= 1e-10 * m_ubar.l2_norm()) return true;
    }
    return false;
  }

  /// The nonlinear step: backward Euler with Newton, or the static solve by load continuation
  /// (the loads and prescribed values scaled from 0 to 1 in increments that grow after a
  /// converged solve and halve after a failed one).
  void step_nonlinear(double t_new) {
    load_vector(t_new, m_f);
    m_ubar = m_u;
    for (const auto d : m_owned)
      if (m_support_of[d] >= 0) m_ubar[d] = prescribed(d, t_new);
    m_ubar.compress(dealii::VectorOperation::insert);
    if (m_opt.static_solve) {
      const Vector target = m_ubar;
      Vector accepted = m_u;
      double s = 0, ds = 0.125;
      while (s < 1) {
        const double s1 = std::min(1.0, s + ds);
        m_ubar = accepted;
        for (const auto d : m_owned)
          if (m_support_of[d] >= 0) m_ubar[d] = s1 * target[d];
        m_ubar.compress(dealii::VectorOperation::insert);
        if (newton(s1)) {
          s = s1;
          accepted = m_ubar;
          ds = std::min(0.5, 1.5 * ds);
        } else if ((ds /= 2) < 1e-4) {
          return fail_nonlinear("Newton did not converge at load factor " + std::to_string(s1), t_new);
        }
      }
      m_ubar = accepted;
      m_u = m_ubar;
      return;
    }
    if (!newton(1.0)) return fail_nonlinear("Newton did not converge in the step", t_new);
    for (const auto d : m_owned) {
      double v = m_v[d], a = m_a[d];
      m_scheme.update(m_ubar[d], m_u[d], 0.0, 0.0, v, a);
      m_v[d] = v;
      m_a[d] = a;
    }
    m_a.compress(dealii::VectorOperation::insert);
    m_v.compress(dealii::VectorOperation::insert);
    m_u = m_ubar;
  }

  /// Stops a nonlinear run as unstable (run() reports why and when): the state turns
  /// non-finite, which the time loop's check catches.
  void fail_nonlinear(const std::string& why, double t) {
    m_nonlinear_failure = "fem (nonlinear): " + why;
    m_failure_time = t;
    m_u = std::numeric_limits<double>::quiet_NaN();
  }

  /// Probes, reactions (from the residual R = M a + C v + K u - f at the constrained dofs: the
  /// force each support exerts on the body) and the nodal field, summed over the ranks (each
  /// owns its dofs); the largest principal strain at the cell centres, max over the ranks.
  void record(double t, Trajectory<dim>& out, bool record_field) {
    out.t.push_back(t);
    std::vector<double> field(static_cast<std::size_t>(m_model.num_nodes()) * dim, 0.0);
    for (std::size_t k = 0; k < field.size(); ++k)
      if (m_node[k] != kUnseen && m_owned.is_element(m_node[k])) field[k] = m_u[m_node[k]];
    m_backend.sum(field);
    std::vector<Vec<dim>> pu;
    for (const auto& [name, node] : m_model.probes)
      pu.push_back(Eigen::Map<const Vec<dim>>(field.data() + static_cast<std::size_t>(node) * dim));
    out.probe_u.push_back(pu);
    load_vector(t, m_f);
    if (m_opt.nonlinear) {
      nonlinear_force(m_u, m_v, m_rhs, 0.0, false);
      if (!m_opt.static_solve) {
        m_tmp = m_a;
        m_tmp.add(m_mat.mass_damping, m_v);
        m_M.vmult_add(m_rhs, m_tmp);
      }
    } else {
      m_K.vmult(m_rhs, m_u);
    }
    if (!m_opt.nonlinear && !m_opt.static_solve) {
      m_C.vmult(m_tmp, m_v);
      m_rhs += m_tmp;
      m_M.vmult(m_tmp, m_a);
      m_rhs += m_tmp;
    }
    m_rhs -= m_f;
    std::vector<double> reac(m_model.supports.size() * dim, 0.0);
    for (const auto d : m_owned)
      if (m_support_of[d] >= 0) reac[static_cast<std::size_t>(m_support_of[d]) * dim + m_comp[d]] += m_rhs[d];
    m_backend.sum(reac);
    std::vector<Vec<dim>> r(m_model.supports.size());
    for (std::size_t s = 0; s < r.size(); ++s) r[s] = Eigen::Map<const Vec<dim>>(reac.data() + s * dim);
    out.reaction.push_back(r);
    const Eigen::Map<const Nodal<dim>> nodal(field.data(), dim, m_model.num_nodes());
    if (record_field) out.field.push_back(nodal);
    // Rotation from the field at the scene's nodes on the scene's cells (the P1 interpolant:
    // the same measure as the spring solvers; every rank holds the summed field).
    const double rotation = max_rotation(m_model.mesh, Nodal<dim>(nodal));
    if (!(rotation <= m_max_rotation)) m_max_rotation = rotation;
    m_ghosted = m_u;
    m_max_strain = std::max(m_max_strain, m_backend.max(max_principal_strain(m_mapping, m_fe, m_dofs, m_ghosted)));
    if (m_opt.frames_dir.empty()) return;
    m_frame_prev = m_frame_last; // the FE fields of the last two samples, for the frames
    m_frame_last = m_ghosted;
    if (out.t.size() == 1) write_frame(m_frame_last, 0);
  }

  /// The samples within the last step (time_loop.hh), and their frames, blended like the
  /// samples from the FE fields at the step's ends.
  void interpolate_samples(Trajectory<dim>& out, std::span<const double> times) {
    const double ta = out.t[out.t.size() - 2], tb = out.t.back();
    interpolate_last_step(out, times);
    if (m_opt.frames_dir.empty()) return;
    for (std::size_t k = 0; k < times.size(); ++k) {
      const double w = step_weight(ta, tb, times[k]);
      m_frame_mix = m_frame_last;
      m_frame_mix.sadd(w, 1 - w, m_frame_prev);
      write_frame(m_frame_mix, out.t.size() - (times.size() - k));
    }
  }

  /// The displacement on the (refined, possibly P2) FE mesh, as deal.II writes it (one
  /// process: run_scene refuses frames under MPI).
  void write_frame(const Vector& u, std::size_t index) {
    dealii::DataOut<dim> data_out;
    data_out.attach_dof_handler(m_dofs);
    const std::vector<std::string> names(dim, "displacement");
    const std::vector<dealii::DataComponentInterpretation::DataComponentInterpretation> kinds(
        dim, dealii::DataComponentInterpretation::component_is_part_of_vector);
    data_out.add_data_vector(u, names, dealii::DataOut<dim>::type_dof_data, kinds);
    data_out.build_patches(m_mapping, static_cast<unsigned int>(m_opt.degree));
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.vtu", index);
    write_file_atomically(m_opt.frames_dir / name, [&](std::ostream& f) { data_out.write_vtu(f); });
  }

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
  typename Backend::Solver m_solver, m_newton;
  Vector m_u, m_v, m_a, m_f, m_rhs, m_tmp, m_ubar, m_delta, m_da, m_dv;
  Vector m_ghosted, m_ghosted_v, m_frame_prev, m_frame_last, m_frame_mix;
  double m_max_strain = 0, m_max_rotation = 0;
  std::string m_nonlinear_failure; ///< why a nonlinear run stopped, empty while it runs
  double m_failure_time = -1;
  std::ostringstream m_timer_stream;
  dealii::TimerOutput m_timer;
};

} // namespace vtb::fem
