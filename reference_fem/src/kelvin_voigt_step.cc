// The Kelvin-Voigt reference's time step: loads, the initial state, the linear step and the nonlinear (Newton) step.
// Members of KelvinVoigtProblem (kelvin_voigt_problem.hh), instantiated for both backends.
#include "kelvin_voigt_problem.hh"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_values.h>

#include <Eigen/Dense>

#include <algorithm>
#include <limits>
namespace vtb::fem {

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::load_vector(double t, Vector& f) {
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

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::add_tractions(const std::vector<dealii::Tensor<1, dim>>& traction, Vector& f) {
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

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::zero_prescribed(Vector& v) {
  for (const auto d : m_owned)
    if (m_support_of[d] >= 0) v[d] = 0;
  v.compress(dealii::VectorOperation::insert);
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::initial_state() {
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
  decltype(m_solver) mass;
  mass.iterative = m_solver.iterative;
  if (mass.iterative) mass.amg.copy_settings(m_solver.amg);
  mass.factor(m_M0);
  mass.solve(m_a, m_rhs);
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::step(double t_new) {
  if (m_opt.nonlinear()) return step_nonlinear(t_new);
  load_vector(m_scheme.load_time(t_new), m_rhs);
  m_scheme.add_history(m_M, m_C, m_K, m_u, m_v, m_a, m_da, m_dv, m_tmp, m_rhs);
  m_ubar = m_u;
  for (const auto d : m_owned)
    if (m_support_of[d] >= 0) m_ubar[d] = prescribed(d, t_new);
  m_ubar.compress(dealii::VectorOperation::insert);
  (m_opt.static_solve ? m_K : m_A).vmult(m_tmp, m_ubar); // static: A = K (matrices_read)
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

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::nonlinear_force(const Vector& u, const Vector& v, Vector& f, double rate,
                                                       bool tangent) {
  m_ghosted = u;
  m_ghosted_v = v;
  m_min_J = std::numeric_limits<double>::infinity();
  f = 0;
  if (tangent) m_T = 0;
  assemble_nonlinear<dim>(m_mapping, m_fe, m_dofs, m_mat, m_opt.degree, m_ghosted, m_ghosted_v, m_constraints,
                          NonlinearTargets<dim, Vector, Matrix>{&f, tangent ? &m_T : nullptr, rate,
                                                                m_opt.kinematics == Kinematics::neo_hookean, &m_min_J});
}

template <int dim, class Backend> double KelvinVoigtProblem<dim, Backend>::volume_ratio(const Vector& u) {
  m_ghosted = u;
  return -m_backend.max(-smallest_volume_ratio<dim>(m_mapping, m_fe, m_dofs, m_opt.degree, m_ghosted));
}

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::residual(double load_scale, Vector& r, bool tangent) {
  const bool dynamic = !m_opt.static_solve;
  const double dt = m_opt.dt, rate = dynamic ? 1 / dt : 0.0;
  m_dv = m_ubar;
  m_dv -= m_u;
  m_dv *= rate;
  nonlinear_force(m_ubar, m_dv, r, rate, tangent);
  if (dynamic && tangent) m_T.add(1 / (dt * dt) + m_mat.mass_damping / dt, m_M0); // prescribed rows eliminated
  r.add(-load_scale, m_f);
  if (dynamic) {
    m_tmp = m_dv;
    m_tmp -= m_v;
    m_tmp *= 1 / dt;
    m_tmp.add(m_mat.mass_damping, m_dv);
    m_M.vmult_add(r, m_tmp);
  }
  zero_prescribed(r);
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::line_search(double load_scale, double g0) {
  // m_ubar = u0 - m_delta. G(eta) = delta . R(u0 - eta delta) is minus the slope of the step's
  // potential along the correction; G(0) = delta . T delta = g0 > 0 where the tangent is positive
  // along it, and G'(0) = -g0 exactly. A step past which the potential rises as steeply as it
  // fell (G(1) < -kOvershootRatio g0) is shortened to where |G| <= kLineSearchRatio g0 (Bonet
  // and Wood's quadratic, Nonlinear Continuum Mechanics for FE Analysis, then regula falsi); a
  // step that falls short, or overshoots less, is kept whole: measured on graded disc presses,
  // shortening every step that overshoots at all (the ratio at 0.5) cost Newton 17 iterations
  // where whole steps took 11.
  if (!(g0 > 0)) return;
  residual(load_scale, m_trial, false);
  double g = m_delta * m_trial;
  if (std::isfinite(g) && g >= -kOvershootRatio * g0) return;
  ++m_newton_stats.line_searches;
  double lo = 0, g_lo = g0, hi = 1, g_hi = g, eta = 1;
  for (int k = 0; k < kLineSearchTrials; ++k) {
    double next = 0.5 * (lo + hi); // a non-finite residual (a cell inverted) bisects
    if (std::isfinite(g_hi)) {
      // First the root of the quadratic through G(0), G'(0) = -g0 and G(1); then regula falsi.
      const double a = g0 / g_hi;
      next = k == 0 ? 0.5 * a + std::sqrt(0.25 * a * a - a) : lo + (hi - lo) * g_lo / (g_lo - g_hi);
    }
    next = std::clamp(next, lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo));
    m_ubar.add(eta - next, m_delta);
    eta = next;
    residual(load_scale, m_trial, false);
    g = m_delta * m_trial;
    if (std::abs(g) <= kLineSearchRatio * g0) break;
    if (g > 0)
      lo = eta, g_lo = g;
    else
      hi = eta, g_hi = std::isfinite(g) ? g : -std::numeric_limits<double>::infinity();
  }
  if (!std::isfinite(g)) m_ubar.add(eta - 1, m_delta); // the whole step (finite: newton checked it)
}

template <int dim, class Backend> bool KelvinVoigtProblem<dim, Backend>::newton(double load_scale, int max_iterations) {
  const bool dynamic = !m_opt.static_solve;
  double first = -1, last_r = -1, forcing = kFirstForcing;
  // A static increment that has not converged in 30 iterations is halved; a residual 1e6 times
  // the first has diverged. (At 12, the former cap, a graded neo-Hookean disc press of 49,026
  // dofs cut its increments 8 times and took 770 s; at 30, no cut and 100 s: from the secant
  // predictor's start Newton converges, if in more than 12 iterations on the deepest increment.)
  const int iterations = max_iterations > 0 ? max_iterations : dynamic ? 25 : 30;
  int backtracks = 0;
  const auto halve = [&] { // the last correction, taken back by half
    ++backtracks;
    ++m_newton_stats.backtracks;
    m_delta *= 0.5;
    m_ubar += m_delta;
  };
  for (int it = 0; it < iterations; ++it) {
    residual(load_scale, m_rhs, true);
    const double r = m_rhs.l2_norm();
    if (!std::isfinite(r)) {
      // The last correction inverted a cell (neo-Hookean's log J <= 0 gives NaN): backtrack by
      // halving it, up to 10 times (1/1024 of the step), before the increment itself is halved.
      if (it == 0 || backtracks >= 10) return false;
      halve();
      --it;
      continue;
    }
    ++m_newton_stats.iterations;
    if (first < 0) first = std::max(r, load_scale * m_f.l2_norm());
    if (r > 1e6 * first) return false;
    if (r <= 1e-9 * first) return true;
    if (m_newton.iterative) {
      // Inexact Newton (Eisenstat and Walker 1996, choice 2): the correction solved to a forcing
      // eta = 0.9 (r / r_last)^2 of its residual (safeguarded against a sudden drop, at most
      // kFirstForcing), never tighter than Newton's own test needs (half of 1e-9 first / r)
      // nor than kFinestForcing. Newton's test on the residual alone decides convergence, so the
      // answer is the exact-Newton one to that test.
      if (last_r > 0) {
        const double safeguard = 0.9 * forcing * forcing;
        forcing = 0.9 * (r / last_r) * (r / last_r);
        if (safeguard > 0.1) forcing = std::max(forcing, safeguard);
        forcing = std::min(forcing, kFirstForcing);
      }
      forcing = std::max({forcing, 0.5e-9 * first / r, kFinestForcing});
      m_newton.amg.set_tolerance(forcing);
      last_r = r;
    }
    m_newton.update(m_T);
    m_newton.solve(m_delta, m_rhs);
    m_ubar -= m_delta;
    // Round-off bounds the residual at about cond(K) 1e-16 of the load (6e-7 of it on a thin
    // cantilever, cond ~ 1e9): a whole correction of 1e-10 of the displacement has converged too.
    const bool negligible = m_delta.l2_norm() <= 1e-10 * m_ubar.l2_norm();
    // A correction that inverts a cell is halved before anything is assembled at it (a pass of
    // gradients, a fraction of an assembly with the tangent); the residual's NaN test above
    // stays the law's own guard. A halved correction is no sign of convergence: the next
    // iteration assembles at it.
    bool halved = false;
    while (m_opt.kinematics == Kinematics::neo_hookean && backtracks < 10 && !(volume_ratio(m_ubar) > 0)) {
      halve();
      halved = true;
    }
    if (negligible && !halved) return true;
    // m_rhs still holds the residual at the correction's start, m_delta the step (halved or not).
    if (m_opt.line_search) line_search(load_scale, m_delta * m_rhs);
  }
  return false;
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::step_nonlinear(double t_new) {
  load_vector(t_new, m_f);
  m_ubar = m_u;
  for (const auto d : m_owned)
    if (m_support_of[d] >= 0) m_ubar[d] = prescribed(d, t_new);
  m_ubar.compress(dealii::VectorOperation::insert);
  if (m_opt.static_solve) {
    // The path starts at the last equilibrium (a static path's previous sample) or, the first
    // time, at no load and no prescribed displacement.
    const bool continued = m_static_time >= 0;
    const Vector target = m_ubar, f_new = m_f;
    Vector accepted = m_u, f_old = m_f;
    const Vector u_old = m_u;
    f_old = 0;
    if (continued) load_vector(m_static_time, f_old);
    m_static_time = t_new;
    // From rest the first increment is an eighth of the load; along a path, the whole step to
    // the next sample (halved until Newton converges, then grown by half each success).
    double s = 0, ds = continued ? 1.0 : 0.125;
    // The secant predictor: from the second increment on, each starts from the last two
    // equilibria (s_prev, previous; s, accepted) extrapolated to its load factor, not from the last
    // one, so that Newton starts near the path. Where it fails (the extrapolated guess inverts a
    // cell, or Newton does not converge from it), the same increment starts again from the last
    // equilibrium before it is halved. On a graded neo-Hookean disc press (1,387 nodes, P2,
    // 0.48 E under the disc) the path took 4 increments and 35 s with it, 9 increments (6 cuts)
    // and 239 s without (docs/fem.md).
    double s_prev = -1;
    bool predict = true;
    // Nested iteration: the whole load at once from the coarser level's answer (start_from).
    // On the graded neo-Hookean disc press refined once, Newton converges from it where the
    // continuation from rest takes four increments (docs/fem.md, "Nested iteration").
    if (!continued && m_start) {
      if (guess_from_coarse()) {
        for (const auto d : m_owned)
          if (m_support_of[d] >= 0) m_ubar[d] = target[d];
        m_ubar.compress(dealii::VectorOperation::insert);
        if ((m_opt.kinematics != Kinematics::neo_hookean || volume_ratio(m_ubar) > 0) &&
            newton(1.0, kNestedIterations)) {
          s = 1;
          accepted = m_ubar;
          m_nested_converged = true;
          m_min_J_accepted = std::min(m_min_J_accepted, m_min_J);
          ++m_newton_stats.increments;
        }
      }
    }
    const auto secant = [&] { return predict && s_prev >= 0 && m_opt.secant_predictor; };
    Vector previous = accepted;
    // A law that softens to a limit point (St. Venant-Kirchhoff collapses under compression)
    // makes the increments shrink without end: 40 increments (a smooth path takes 5 to 20) say so.
    for (int increments = 0; s < 1; ++increments) {
      if (increments == 40)
        return fail_nonlinear("the load continuation stalled at load factor " + std::to_string(s) +
                                  " (a limit point: the law softens to collapse)",
                              t_new);
      const double s1 = std::min(1.0, s + ds);
      // The increment's start: the last equilibrium, or the secant's extrapolation from it
      // (u(s1) ~ u(s) + (s1 - s) / (s - s_prev) (u(s) - u(s_prev))) unless that inverts a cell.
      for (const bool extrapolate : {secant(), false}) {
        m_ubar = accepted;
        if (extrapolate) {
          m_tmp = accepted;
          m_tmp -= previous;
          m_ubar.add((s1 - s) / (s - s_prev), m_tmp);
        }
        for (const auto d : m_owned)
          if (m_support_of[d] >= 0) m_ubar[d] = continued ? u_old[d] + s1 * (target[d] - u_old[d]) : s1 * target[d];
        m_ubar.compress(dealii::VectorOperation::insert);
        if (!extrapolate || m_opt.kinematics != Kinematics::neo_hookean || volume_ratio(m_ubar) > 0) break;
      }
      if (continued) { // the load between the two samples' (newton takes m_f as the load at factor 1)
        m_f = f_new;
        m_f -= f_old;
        m_f *= s1;
        m_f += f_old;
      }
      const bool converged = newton(continued ? 1.0 : s1);
      if (converged) {
        previous = accepted;
        s_prev = s;
        s = s1;
        accepted = m_ubar;
        ds = std::min(0.5, 1.5 * ds);
        predict = true;
        m_min_J_accepted = std::min(m_min_J_accepted, m_min_J);
        ++m_newton_stats.increments;
      } else if (secant()) {
        predict = false; // the same increment again from the last equilibrium (not a new increment)
        --increments;
      } else if ((ds /= 2) < 1e-4) {
        return fail_nonlinear("Newton did not converge at load factor " + std::to_string(s1), t_new);
      } else {
        predict = true;
        ++m_newton_stats.cuts;
      }
    }
    m_ubar = accepted;
    m_u = m_ubar;
    return;
  }
  if (!newton(1.0)) return fail_nonlinear("Newton did not converge in the step", t_new);
  m_min_J_accepted = std::min(m_min_J_accepted, m_min_J);
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

template <int dim, class Backend> bool KelvinVoigtProblem<dim, Backend>::guess_from_coarse() {
  for (const auto d : m_owned) {
    const auto v = m_start->at(m_point[d]);
    if (!v) return false;
    m_ubar[d] = (*v)[m_comp[d]];
  }
  m_ubar.compress(dealii::VectorOperation::insert);
  return true;
}

template <int dim, class Backend>
LevelAnswer<dim> KelvinVoigtProblem<dim, Backend>::answer(double tolerance, MPI_Comm comm) {
  // The field at the barycentric quarters of every owned cell (LevelAnswer in grid.hh).
  std::vector<dealii::Point<dim>> quarters;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; i + j <= 4; ++j)
      for (int k = 0; k <= (dim == 3 ? 4 - i - j : 0); ++k) {
        dealii::Point<dim> p;
        p[0] = i / 4.0, p[1] = j / 4.0;
        if constexpr (dim == 3) p[2] = k / 4.0;
        quarters.push_back(p);
      }
  const dealii::Quadrature<dim> points(quarters);
  dealii::FEValues<dim> fev(m_mapping, m_fe, points, dealii::update_values | dealii::update_quadrature_points);
  const dealii::FEValuesExtractors::Vector disp(0);
  std::vector<dealii::Tensor<1, dim>> values(points.size());
  m_ghosted = m_u;
  LevelAnswer<dim> a(tolerance);
  for (const auto& cell : m_dofs.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fev.reinit(cell);
    fev[disp].get_function_values(m_ghosted, values);
    for (unsigned int q = 0; q < points.size(); ++q) a.add(fev.quadrature_point(q), values[q]);
  }
  a.gather(comm);
  return a;
}

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::fail_nonlinear(const std::string& why, double t) {
  m_nonlinear_failure = std::string("fem (") + kinematics_name(m_opt.kinematics) + "): " + why;
  m_failure_time = t;
  m_u = std::numeric_limits<double>::quiet_NaN();
}

template class KelvinVoigtProblem<2, SerialBackend<2>>;
template class KelvinVoigtProblem<3, SerialBackend<3>>;
template class KelvinVoigtProblem<2, DistributedBackend<2>>;
template class KelvinVoigtProblem<3, DistributedBackend<3>>;

} // namespace vtb::fem
