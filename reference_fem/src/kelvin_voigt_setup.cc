// The Kelvin-Voigt reference's set-up: the run, the dofs, the supports, the assembly.
// Members of KelvinVoigtProblem (kelvin_voigt_problem.hh), instantiated for both backends.
#include "kelvin_voigt_problem.hh"
#include "vtb/problem/solver_names.hh"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <algorithm>
#include <chrono>
#include <map>
namespace vtb::fem {

template <int dim, class Backend>
RunReport KelvinVoigtProblem<dim, Backend>::run(Trajectory<dim>& out, bool record_field) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  {
    dealii::TimerOutput::Scope s(m_timer, "setup");
    m_backend.create(m_model, m_opt.refinements, *m_tria, m_loads_of_id);
    setup_dofs();
    setup_nodes();
    setup_constraints();
    choose_solvers();
  }
  {
    dealii::TimerOutput::Scope s(m_timer, "assembly");
    assemble();
  }
  {
    dealii::TimerOutput::Scope s(m_timer, "factorisation");
    if (!m_opt.nonlinear()) m_solver.factor(m_A0); // Newton solves with its tangent alone
    initial_state();
  }
  RunReport rep = header();
  rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  march(
      m_scheme, m_model.duration, m_model.output_interval, rep,
      [&](double t) {
        {
          dealii::TimerOutput::Scope s(m_timer, "time stepping");
          step(t);
        }
        if (m_opt.progress) m_opt.progress(std::min(1.0, t / m_model.duration));
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
  report_solvers(rep);
  rep.max_strain = m_max_strain;
  rep.max_rotation = m_max_rotation;
  for (const auto& [phase, seconds] : m_timer.get_summary_data(dealii::TimerOutput::total_wall_time)) {
    std::string key = "phase_" + phase + "_seconds";
    std::replace(key.begin(), key.end(), ' ', '_');
    rep.extra.push_back({key, seconds});
  }
  return rep;
}

template <int dim, class Backend> RunReport KelvinVoigtProblem<dim, Backend>::header() const {
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

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::setup_dofs() {
  m_dofs.distribute_dofs(m_fe);
  m_owned = m_dofs.locally_owned_dofs();
  dealii::DoFTools::extract_locally_relevant_dofs(m_dofs, m_relevant);
  dealii::DynamicSparsityPattern dsp(m_relevant);
  dealii::DoFTools::make_sparsity_pattern(m_dofs, dsp, dealii::AffineConstraints<double>(), true);
  m_backend.reinit(dsp, m_owned, m_relevant, matrices_read());
  for (auto* v : {&m_u, &m_v, &m_a, &m_f, &m_rhs, &m_tmp, &m_ubar, &m_delta, &m_da, &m_dv, &m_trial})
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

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::setup_nodes() {
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

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::setup_constraints() {
  const auto n = m_dofs.n_dofs();
  m_support_of.assign(n, -1);
  const double grow = 1e-9 * bounding_diagonal(m_model.mesh), tol = 1e-10 * bounding_diagonal(m_model.mesh);
  for (std::size_t s = 0; s < m_model.supports.size(); ++s) {
    const auto& sup = m_model.supports[s];
    // The facets' bounding box (grown by tol): a dof outside it is on none of them. Without it,
    // every dof meets every facet (424k dofs x 416 facets: 10 s of a 78 s static solve).
    Eigen::Matrix<double, dim, 1> lo = Eigen::Matrix<double, dim, 1>::Constant(1e300), hi = -lo;
    for (const auto& f : sup.facets)
      for (int v : f) {
        lo = lo.cwiseMin(m_model.mesh.points.col(v));
        hi = hi.cwiseMax(m_model.mesh.points.col(v));
      }
    const auto near_facets = [&](const dealii::Point<dim>& p) {
      for (int a = 0; a < dim; ++a)
        if (p[a] < lo[a] - tol || p[a] > hi[a] + tol) return false;
      return true;
    };
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
      if (!in && near_facets(m_point[d]))
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

template <int dim, class Backend>
std::vector<typename Backend::Matrix*> KelvinVoigtProblem<dim, Backend>::matrices_read() {
  // A static solve's scheme has A = K (ck 1, cm = cc = 0) and no history: step() multiplies
  // with K there, and neither C, M nor M0 is read (record's reactions are K u - f, Newton's
  // residual f_int - f). On a 421,749-dof P2 block (docs/fem.md) two matrices instead of seven:
  // 3.6 GB instead of 5.0, 58 s instead of 72.
  if (m_answers) return {&m_K, &m_M, &m_A0};
  if (m_opt.static_solve) return m_opt.nonlinear() ? std::vector<Matrix*>{&m_T} : std::vector<Matrix*>{&m_K, &m_A0};
  std::vector<Matrix*> all{&m_K, &m_M, &m_C, &m_A, &m_A0, &m_M0};
  if (m_opt.nonlinear()) all.push_back(&m_T);
  return all;
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::assemble() {
  const auto read = matrices_read();
  const auto reads = [&](const Matrix& A) { return std::find(read.begin(), read.end(), &A) != read.end(); };
  if (!reads(m_K)) return; // a nonlinear static solve: the tangent is Newton's to assemble
  const bool mass = reads(m_M), damping = reads(m_C), step = reads(m_A), mass0 = reads(m_M0);
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
    if (mass) none.distribute_local_to_global(m, local, m_M);
    if (damping) none.distribute_local_to_global(c, local, m_C);
    if (step) none.distribute_local_to_global(a, local, m_A);
    if (mass0) m_constraints.distribute_local_to_global(m, local, m_M0);
    m_constraints.distribute_local_to_global(a, local, m_A0);
  }
  for (auto* A : read) A->compress(dealii::VectorOperation::add);
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::choose_solvers() {
  const auto& k = m_opt.linear_solver;
  const auto by_default = [&](bool tangent) {
    return k == "cg" || k == "cg-multigrid" ||
           (k == "auto" && iterative_by_default(dim, static_cast<long>(m_dofs.n_dofs()), m_backend.ranks(), tangent));
  };
  m_solver.iterative = by_default(false);
  m_newton.iterative = by_default(true);
  if (!m_solver.iterative && !m_newton.iterative) return;
  const auto& X = m_model.mesh.points;
  dealii::Point<dim> centre;
  for (int a = 0; a < dim; ++a) centre[a] = 0.5 * (X.row(a).minCoeff() + X.row(a).maxCoeff());
  const int n_modes = m_opt.amg_rotations ? dim * (dim + 1) / 2 : dim;
  auto modes =
      rigid_body_modes<dim>(m_owned, m_point, m_comp, centre, bounding_diagonal(m_model.mesh), m_opt.amg_rotations);
  m_solver.amg.set_null_space(modes, n_modes, dim);
  m_newton.amg.set_null_space(std::move(modes), n_modes, dim);
  // The linear systems to round-off's reach (the direct solve's answer to 1e-8, test FemAmg.*);
  // Newton's corrections to the forcing terms of KelvinVoigtProblem::newton (1e-2 to 1e-8 of their residual); this is
  // its finest.
  m_solver.amg.set_tolerance(1e-12);
  m_newton.amg.set_tolerance(1e-8);
}

template <int dim, class Backend> void KelvinVoigtProblem<dim, Backend>::report_solvers(RunReport& rep) const {
  const bool newton = m_opt.nonlinear();
  const bool iterative = newton ? m_newton.iterative : m_solver.iterative;
  rep.extra.push_back({"iterative_solver", iterative ? 1.0 : 0.0});
  if (newton) {
    rep.extra.push_back({"newton_iterations", static_cast<double>(m_newton_stats.iterations)});
    rep.extra.push_back({"newton_backtracks", static_cast<double>(m_newton_stats.backtracks)});
    rep.extra.push_back({"newton_line_searches", static_cast<double>(m_newton_stats.line_searches)});
    // The smallest det F at a quadrature point of any accepted state: how near the solid came to
    // inverting (the springs' min_volume_ratio measures their cells the same way).
    const double smallest = -m_backend.max(-m_min_J_accepted); // +inf before an accepted state
    rep.extra.push_back({"min_volume_ratio", std::isfinite(smallest) ? smallest : 1.0});
    if (m_start) rep.extra.push_back({"nested_start_converged", m_nested_converged ? 1.0 : 0.0});
    if (m_opt.static_solve) {
      rep.extra.push_back({"load_increments", static_cast<double>(m_newton_stats.increments)});
      rep.extra.push_back({"load_increment_cuts", static_cast<double>(m_newton_stats.cuts)});
    }
  }
  if (!iterative) return;
  const KrylovStats& s = newton ? m_newton.amg.stats() : m_solver.amg.stats();
  rep.extra.push_back({"krylov_solves", static_cast<double>(s.solves)});
  rep.extra.push_back({"krylov_iterations_mean",
                       s.solves > 0 ? static_cast<double>(s.iterations) / static_cast<double>(s.solves) : 0.0});
  rep.extra.push_back({"krylov_iterations_max", static_cast<double>(s.max_iterations)});
  rep.extra.push_back({"amg_setups", static_cast<double>(s.setups)});
}

template class KelvinVoigtProblem<2, SerialBackend<2>>;
template class KelvinVoigtProblem<3, SerialBackend<3>>;
template class KelvinVoigtProblem<2, DistributedBackend<2>>;
template class KelvinVoigtProblem<3, DistributedBackend<3>>;

} // namespace vtb::fem
