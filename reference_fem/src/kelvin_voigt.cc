// The Kelvin-Voigt finite element reference, in the style of the deal.II tutorials (step-8,
// step-18, step-23): one problem class with setup_system / assemble_system / solve_step /
// record, and a run function that drives them.
//
// The semi-discrete problem is  M a + C v + K u = f(t),  with K the linear elasticity
// stiffness (plane stress with thickness t in 2D), M the consistent mass, and the Voigt
// damping C = tau K + gamma M (sigma = C : (eps + tau eps_dot), mass damping gamma).
// Every time scheme solves for the new displacement with one constant matrix:
//   backward Euler:  (M / dt^2 + C / dt + K) u+ = f+ + M (u / dt^2 + v / dt) + C u / dt
//   Newmark family with generalized-alpha weights (Chung and Hulbert 1993):
//     (1 - am) M a+ + am M a + (1 - af) (C v+ + K u+) + af (C v + K u) = f(t + (1 - af) dt),
//     u+ = u + dt v + dt^2 ((1/2 - beta) a + beta a+),  v+ = v + dt ((1 - gamma) a + gamma a+),
//   so that a+ = c1 u+ + d_a, v+ = c2 u+ + d_v with c1 = 1 / (beta dt^2), c2 = gamma / (beta dt),
//   and ((1 - am) c1 M + (1 - af) c2 C + (1 - af) K) u+ = the rest.
//   `newmark` is average acceleration (am = af = 0, beta = 1/4, gamma = 1/2: second order,
//   no numerical damping); `generalized-alpha` uses rho_inf = 0 (asymptotic annihilation: second order, removes the
//   highest modes, which a step load or a kink of a drive excites and average acceleration
//   keeps ringing: on the 123-node plate its clamp reaction lagged the step load by 0.2 s;
//   with rho_inf = 0.8 it still lagged 0.1 s, with 0 it is right after one step).
// Prescribed displacements (fixes, drives) are imposed by lifting: u+ = u_bar + delta, with
// u_bar holding the prescribed values, and A0 delta = b - A u_bar, where A0 is A with the
// constrained rows and columns replaced by the identity (factorised once, UMFPACK).
// The scheme's formulas are in time_scheme.hh, shared with the distributed solver.
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/core/solver_names.hh"

#include "grid.hh"
#include "time_loop.hh"
#include "time_scheme.hh"
#include "vtb/meshes/atomic_file.hh"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/timer.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_out.h>

#include <Eigen/Eigenvalues>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace vtb::fem {
namespace {

using namespace dealii;

template <int dim> class KelvinVoigtProblem {
public:
  KelvinVoigtProblem(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options)
      : m_model(model), m_mat(material), m_opt(options), m_scheme(options.scheme, options.static_solve, options.dt),
        m_fe(FE_SimplexP<dim>(options.degree), dim), m_mapping(FE_SimplexP<dim>(1)), m_dofs(m_tria),
        m_timer(m_timer_stream, TimerOutput::never, TimerOutput::wall_times) {}

  RunReport run(Trajectory<dim>& out, bool record_field);

private:
  void make_grid();
  void setup_system();
  void assemble_system();
  void setup_constraints();
  /// Prescribed displacement of constrained dofs at time t (u_bar's constrained entries).
  double prescribed(types::global_dof_index dof, double t) const;
  void load_vector(double t, Vector<double>& f) const;
  void solve_step(double t_new);
  void initial_state();
  void record(double t, Trajectory<dim>& out, bool record_field, RunReport& rep);
  void write_frame(const Vector<double>& u, std::size_t index);

  const Problem<dim>& m_model;
  const MaterialDesc& m_mat;
  const FemOptions m_opt;
  const TimeScheme m_scheme;

  Triangulation<dim> m_tria;
  FESystem<dim> m_fe;
  MappingFE<dim> m_mapping;
  DoFHandler<dim> m_dofs;
  std::map<std::set<int>, types::boundary_id> m_load_ids; ///< set of loads on a facet -> id
  std::vector<std::vector<int>> m_loads_of_id;            ///< id -> loads

  SparsityPattern m_pattern;
  SparseMatrix<double> m_K, m_M, m_C, m_A, m_A0;
  SparseDirectUMFPACK m_solver;

  std::vector<Point<dim>> m_support;                            ///< per dof
  std::vector<int> m_component;                                 ///< per dof
  std::vector<int> m_support_of;                                ///< per dof: support index or -1
  std::vector<std::array<types::global_dof_index, dim>> m_node; ///< original node -> its dofs
  std::vector<std::vector<types::global_dof_index>> m_point_load_dofs;

  Vector<double> m_u, m_v, m_a, m_f, m_rhs, m_tmp, m_ubar, m_delta, m_da, m_dv;
  Vector<double> m_frame_prev, m_frame_last, m_frame_mix;
  std::ostringstream m_timer_stream;
  TimerOutput m_timer;
};

/// The scene's mesh as a deal.II triangulation (see make_triangulation).
template <int dim> void KelvinVoigtProblem<dim>::write_frame(const Vector<double>& u, std::size_t index) {
  // The displacement on the (refined, possibly P2) FE mesh, as deal.II writes it.
  DataOut<dim> data_out;
  data_out.attach_dof_handler(m_dofs);
  const std::vector<std::string> names(dim, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> kinds(
      dim, DataComponentInterpretation::component_is_part_of_vector);
  data_out.add_data_vector(u, names, DataOut<dim>::type_dof_data, kinds);
  data_out.build_patches(m_mapping, static_cast<unsigned int>(m_opt.degree));
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04zu.vtu", index);
  write_file_atomically(m_opt.frames_dir / name, [&](std::ostream& f) { data_out.write_vtu(f); });
}

template <int dim> void KelvinVoigtProblem<dim>::make_grid() {
  make_triangulation(m_model, m_opt.refinements, m_tria, m_loads_of_id);
}

template <int dim> void KelvinVoigtProblem<dim>::setup_system() {
  m_dofs.distribute_dofs(m_fe);
  const auto n = m_dofs.n_dofs();
  DynamicSparsityPattern dsp(n, n);
  DoFTools::make_sparsity_pattern(m_dofs, dsp);
  m_pattern.copy_from(dsp);
  for (auto* A : {&m_K, &m_M, &m_C, &m_A, &m_A0}) A->reinit(m_pattern);
  for (auto* v : {&m_u, &m_v, &m_a, &m_f, &m_rhs, &m_tmp, &m_ubar, &m_delta, &m_da, &m_dv}) v->reinit(n);

  // Support points and components of every dof; the dofs of the original nodes.
  m_support.assign(n, Point<dim>());
  m_component.assign(n, 0);
  const auto& unit = m_fe.get_unit_support_points();
  FEValues<dim> fev(m_mapping, m_fe, Quadrature<dim>(unit), update_quadrature_points);
  std::vector<types::global_dof_index> local(m_fe.n_dofs_per_cell());
  for (const auto& cell : m_dofs.active_cell_iterators()) {
    fev.reinit(cell);
    cell->get_dof_indices(local);
    for (unsigned int i = 0; i < local.size(); ++i) {
      m_support[local[i]] = fev.quadrature_point(i);
      m_component[local[i]] = static_cast<int>(m_fe.system_to_component_index(i).first);
    }
  }
  std::map<std::vector<double>, std::array<types::global_dof_index, dim>> by_point;
  for (types::global_dof_index d = 0; d < n; ++d) {
    std::vector<double> key(m_support[d].begin_raw(), m_support[d].end_raw());
    by_point[key][static_cast<std::size_t>(m_component[d])] = d;
  }
  const Mesh<dim>& mesh = m_model.mesh;
  m_node.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Point<dim> p = to_point<dim>(mesh.points.col(i));
    const auto it = by_point.find(std::vector<double>(p.begin_raw(), p.end_raw()));
    if (it == by_point.end()) throw std::runtime_error("fem: node " + std::to_string(i) + " is not a support point");
    m_node[static_cast<std::size_t>(i)] = it->second;
  }
}

/// K, M and C = tau K + gamma M, by quadrature of degree 2p (exact for the affine simplices).
template <int dim> void KelvinVoigtProblem<dim>::assemble_system() {
  const QGaussSimplex<dim> quad(static_cast<unsigned int>(m_opt.degree + 1));
  FEValues<dim> fev(m_mapping, m_fe, quad, update_values | update_gradients | update_JxW_values);
  const unsigned int nd = m_fe.n_dofs_per_cell();
  FullMatrix<double> k(nd, nd), m(nd, nd);
  std::vector<types::global_dof_index> local(nd);
  for (const auto& cell : m_dofs.active_cell_iterators()) {
    fev.reinit(cell);
    element_matrices(fev, m_fe, m_mat, k, m);
    cell->get_dof_indices(local);
    for (unsigned int i = 0; i < nd; ++i)
      for (unsigned int j = 0; j < nd; ++j) {
        m_K.add(local[i], local[j], k(i, j));
        m_M.add(local[i], local[j], m(i, j));
      }
  }
  m_C.copy_from(m_K);
  m_C *= m_mat.retardation_time;
  m_C.add(m_mat.mass_damping, m_M);
}

/// Which dofs each support prescribes: for a box, the support points inside it; for a group,
/// the support points on its facets and its nodes; for a point, the dofs of its node.
template <int dim> void KelvinVoigtProblem<dim>::setup_constraints() {
  const auto n = m_dofs.n_dofs();
  m_support_of.assign(n, -1);
  const double grow = 1e-9 * bounding_diagonal(m_model.mesh);
  const double tol = 1e-10 * bounding_diagonal(m_model.mesh);

  for (std::size_t s = 0; s < m_model.supports.size(); ++s) {
    const auto& sup = m_model.supports[s];
    std::vector<types::global_dof_index> dofs;
    if (sup.box) {
      for (types::global_dof_index d = 0; d < n; ++d) {
        bool in = true;
        for (int a = 0; a < dim; ++a)
          in = in && m_support[d][a] >= sup.box->min[a] - grow && m_support[d][a] <= sup.box->max[a] + grow;
        if (in) dofs.push_back(d);
      }
    } else {
      for (int node : sup.nodes)
        for (auto d : m_node[static_cast<std::size_t>(node)]) dofs.push_back(d);
      if (!sup.facets.empty())
        for (types::global_dof_index d = 0; d < n; ++d)
          for (const auto& f : sup.facets)
            if (on_facet<dim>(m_model.mesh, m_support[d], f, tol)) {
              dofs.push_back(d);
              break;
            }
    }
    for (auto d : dofs) m_support_of[d] = static_cast<int>(s);
  }
  // Point loads act on their node's dofs.
  for (const auto& l : m_model.loads) {
    std::vector<types::global_dof_index> d;
    if (l.facets.empty())
      for (int node : l.nodes)
        for (auto dof : m_node[static_cast<std::size_t>(node)]) d.push_back(dof);
    m_point_load_dofs.push_back(d);
  }
}

template <int dim> double KelvinVoigtProblem<dim>::prescribed(types::global_dof_index dof, double t) const {
  const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of[dof])];
  return s.driven ? ramp_factor(t, s.start, s.ramp) * s.displacement[m_component[dof]] : 0.0;
}

/// f(t): uniform tractions total / |region| integrated over the load facets, and point loads
/// on their node's dofs.
template <int dim> void KelvinVoigtProblem<dim>::load_vector(double t, Vector<double>& f) const {
  f = 0;
  std::vector<Tensor<1, dim>> traction(m_loads_of_id.size());
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
  const double thick = dim == 2 ? m_mat.thickness : 1.0;
  if (any) {
    const QGaussSimplex<dim - 1> fquad(static_cast<unsigned int>(m_opt.degree + 1));
    FEFaceValues<dim> fv(m_mapping, m_fe, fquad, update_values | update_JxW_values);
    std::vector<types::global_dof_index> local(m_fe.n_dofs_per_cell());
    for (const auto& cell : m_dofs.active_cell_iterators())
      for (const unsigned int face : cell->face_indices()) {
        const auto id = cell->face(face)->boundary_id();
        if (!cell->face(face)->at_boundary() || id == 0 || id >= m_loads_of_id.size()) continue;
        fv.reinit(cell, face);
        cell->get_dof_indices(local);
        for (unsigned int q = 0; q < fquad.size(); ++q)
          for (unsigned int i = 0; i < local.size(); ++i) {
            const unsigned int c = m_fe.system_to_component_index(i).first;
            f[local[i]] += traction[id][c] * fv.shape_value(i, q) * fv.JxW(q) / thick * thick;
          }
      }
  }
  for (std::size_t l = 0; l < m_model.loads.size(); ++l) {
    const auto& load = m_model.loads[l];
    if (!load.facets.empty()) continue;
    const double s = ramp_factor(t, load.start, load.ramp);
    for (std::size_t k = 0; k < load.nodes.size(); ++k)
      for (int a = 0; a < dim; ++a)
        f[m_node[static_cast<std::size_t>(load.nodes[k])][static_cast<std::size_t>(a)]] +=
            s * load.force(a, static_cast<Eigen::Index>(k));
  }
}

template <int dim> void KelvinVoigtProblem<dim>::initial_state() {
  const auto n = m_dofs.n_dofs();
  m_u = 0;
  m_v = 0;
  m_a = 0;
  // The problem holds the initial velocity v(x) = v_lin + w x (x - c) at the mesh's nodes;
  // that field is affine, so interpolating it at the support points is exact: use the affine
  // fit through the nodes.
  const Nodal<dim>& V = m_model.initial_velocity;
  Eigen::Matrix<double, dim + 1, Eigen::Dynamic> X(dim + 1, m_model.num_nodes());
  X.topRows(dim) = m_model.mesh.points;
  X.row(dim).setOnes();
  const Eigen::Matrix<double, dim, dim + 1> affine = (X * X.transpose()).ldlt().solve(X * V.transpose()).transpose();
  for (types::global_dof_index d = 0; d < n; ++d) {
    Eigen::Matrix<double, dim + 1, 1> x;
    for (int a = 0; a < dim; ++a) x[a] = m_support[d][a];
    x[dim] = 1;
    m_v[d] = affine.row(m_component[d]).dot(x);
  }
  for (types::global_dof_index d = 0; d < n; ++d)
    if (m_support_of[d] >= 0) {
      const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of[d])];
      m_u[d] = prescribed(d, 0.0);
      m_v[d] = s.driven ? ramp_rate(0.0, s.start, s.ramp) * s.displacement[m_component[d]] : 0.0;
    }
  // Newmark needs a(0) = M^-1 (f(0-) - C v - K u) on the free dofs.
  if (m_scheme.newmark_family) {
    // The loads as they are just before t = 0: a step at t = 0 acts from the first step on. Its
    // instantaneous acceleration M^-1 F is an impulse that a one-step scheme cannot represent;
    // taken as a(0) it throws the first steps of Newmark (beta = 1/4) and generalized-alpha
    // (beta = 1) far off the solution.
    load_vector(-1e-12 * m_opt.dt, m_f);
    m_rhs = m_f;
    m_C.vmult(m_tmp, m_v);
    m_rhs -= m_tmp;
    m_K.vmult(m_tmp, m_u);
    m_rhs -= m_tmp;
    SparseMatrix<double> M0;
    M0.reinit(m_pattern);
    M0.copy_from(m_M);
    for (types::global_dof_index d = 0; d < n; ++d)
      if (m_support_of[d] >= 0) {
        for (auto it = M0.begin(d); it != M0.end(d); ++it) it->value() = (it->column() == d) ? m_M.diag_element(d) : 0;
        m_rhs[d] = 0;
      }
    for (types::global_dof_index d = 0; d < n; ++d)
      if (m_support_of[d] < 0)
        for (auto it = M0.begin(d); it != M0.end(d); ++it)
          if (m_support_of[it->column()] >= 0) it->value() = 0;
    SparseDirectUMFPACK msolve;
    msolve.initialize(M0);
    msolve.vmult(m_a, m_rhs);
  }
}

/// One step to t_new: u+ from A u+ = b with the prescribed values lifted, then v+ and a+.
template <int dim> void KelvinVoigtProblem<dim>::solve_step(double t_new) {
  const auto n = m_dofs.n_dofs();
  load_vector(m_scheme.load_time(t_new), m_rhs);
  m_scheme.add_history(m_M, m_C, m_K, m_u, m_v, m_a, m_da, m_dv, m_tmp, m_rhs);
  // Lift the prescribed values: u+ = u_bar + delta, A0 delta = rhs - A u_bar, delta = 0 on them.
  m_ubar = m_u;
  for (types::global_dof_index d = 0; d < n; ++d)
    if (m_support_of[d] >= 0) m_ubar[d] = prescribed(d, t_new);
  m_A.vmult(m_tmp, m_ubar);
  m_rhs -= m_tmp;
  for (types::global_dof_index d = 0; d < n; ++d)
    if (m_support_of[d] >= 0) m_rhs[d] = 0;
  m_solver.vmult(m_delta, m_rhs);
  Vector<double>& u_new = m_ubar;
  u_new += m_delta;
  if (m_opt.static_solve) {
    m_u = u_new;
    return;
  }
  for (types::global_dof_index d = 0; d < n; ++d) {
    if (m_scheme.newmark_family && m_support_of[d] >= 0) {
      // On prescribed dofs the motion is known: its rate and (piecewise linear ramps) zero
      // acceleration; the Newmark update would ring there after a kink.
      const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of[d])];
      m_v[d] = s.driven ? ramp_rate(t_new, s.start, s.ramp) * s.displacement[m_component[d]] : 0.0;
      m_a[d] = 0;
      continue;
    }
    m_scheme.update(u_new[d], m_u[d], m_da[d], m_dv[d], m_v[d], m_a[d]);
  }
  m_u = u_new;
}

template <int dim>
void KelvinVoigtProblem<dim>::record(double t, Trajectory<dim>& out, bool record_field, RunReport& rep) {
  out.t.push_back(t);
  std::vector<Vec<dim>> pu;
  for (const auto& [name, node] : m_model.probes) {
    Vec<dim> u;
    for (int a = 0; a < dim; ++a) u[a] = m_u[m_node[static_cast<std::size_t>(node)][static_cast<std::size_t>(a)]];
    pu.push_back(u);
  }
  out.probe_u.push_back(pu);
  // Reactions from the residual R = M a + C v + K u - f at the constrained dofs.
  load_vector(t, m_f);
  m_rhs = 0;
  m_K.vmult(m_rhs, m_u);
  if (!m_opt.static_solve) {
    m_C.vmult_add(m_rhs, m_v);
    m_M.vmult_add(m_rhs, m_a);
  }
  m_rhs -= m_f;
  std::vector<Vec<dim>> reac(m_model.supports.size(), Vec<dim>::Zero());
  for (types::global_dof_index d = 0; d < m_dofs.n_dofs(); ++d)
    if (m_support_of[d] >= 0) reac[static_cast<std::size_t>(m_support_of[d])][m_component[d]] += m_rhs[d];
  out.reaction.push_back(reac);
  if (!m_opt.frames_dir.empty()) {
    m_frame_prev = m_frame_last; // the FE fields of the last two samples, for the frames
    m_frame_last = m_u;
  }
  if (record_field) {
    Nodal<dim> field(dim, m_model.num_nodes());
    for (int i = 0; i < m_model.num_nodes(); ++i)
      for (int a = 0; a < dim; ++a) field(a, i) = m_u[m_node[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)]];
    out.field.push_back(std::move(field));
  }
  rep.max_strain = std::max(rep.max_strain, max_principal_strain(m_mapping, m_fe, m_dofs, m_u));
}

template <int dim> RunReport KelvinVoigtProblem<dim>::run(Trajectory<dim>& out, bool record_field) {
  using clock = std::chrono::steady_clock;
  RunReport rep;
  rep.solver = solvers::kFem;
  rep.dim = dim;
  rep.dt = m_opt.dt;
  rep.duration = m_model.duration;
  const auto t0 = clock::now();
  {
    TimerOutput::Scope s(m_timer, "setup");
    make_grid();
    setup_system();
    setup_constraints();
  }
  {
    TimerOutput::Scope s(m_timer, "assembly");
    assemble_system();
  }
  {
    TimerOutput::Scope s(m_timer, "factorisation");
    m_A.copy_from(m_K);
    m_A *= m_scheme.ck();
    m_A.add(m_scheme.cm(), m_M);
    m_A.add(m_scheme.cc(), m_C);
    m_A0.copy_from(m_A);
    const auto n = m_dofs.n_dofs();
    for (types::global_dof_index d = 0; d < n; ++d) {
      const bool cd = m_support_of[d] >= 0;
      const double diag = m_A.diag_element(d);
      for (auto it = m_A0.begin(d); it != m_A0.end(d); ++it)
        if (cd || m_support_of[it->column()] >= 0) it->value() = (it->column() == d) ? diag : 0;
    }
    m_solver.initialize(m_A0);
    initial_state();
  }
  rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  rep.nodes = m_model.num_nodes();
  rep.extra = {{"cells", static_cast<double>(m_tria.n_active_cells())},
               {"dofs", static_cast<double>(m_dofs.n_dofs())},
               {"degree", static_cast<double>(m_opt.degree)},
               {"refinements", static_cast<double>(m_opt.refinements)}};

  march(
      m_scheme, m_model.duration, m_model.output_interval, rep,
      [&](double t) {
        TimerOutput::Scope s(m_timer, "time stepping");
        solve_step(t);
      },
      [&] { return std::isfinite(m_u.l2_norm()); },
      [&](double t) {
        TimerOutput::Scope s(m_timer, "output");
        record(t, out, record_field, rep);
        if (!m_opt.frames_dir.empty() && out.t.size() == 1) write_frame(m_u, 0);
      },
      [&](std::span<const double> times) {
        TimerOutput::Scope s(m_timer, "output");
        const double ta = out.t[out.t.size() - 2], tb = out.t.back();
        interpolate_last_step(out, times);
        if (m_opt.frames_dir.empty()) return;
        for (std::size_t k = 0; k < times.size(); ++k) {
          const double w = step_weight(ta, tb, times[k]);
          m_frame_mix = m_frame_last;
          m_frame_mix.sadd(w, 1 - w, m_frame_prev);
          write_frame(m_frame_mix, out.t.size() - (times.size() - k));
        }
      });
  for (const auto& [phase, seconds] : m_timer.get_summary_data(TimerOutput::total_wall_time)) {
    std::string key = "phase_" + phase + "_seconds";
    std::replace(key.begin(), key.end(), ' ', '_');
    rep.extra.push_back({key, seconds});
  }
  return rep;
}

} // namespace

FemOptions options_from(const SolverDesc& s) {
  FemOptions o;
  o.degree = s.degree;
  o.refinements = s.refinements;
  o.scheme = s.scheme;
  o.static_solve = s.static_solve;
  o.dt = s.dt;
  return o;
}

template <int dim>
RunReport simulate(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                   Trajectory<dim>& out, bool record_field) {
  if (options.degree < 1 || options.degree > 2) throw InputError("[solver].degree must be 1 or 2");
  if (!(options.dt > 0)) throw InputError("[solver].dt must be > 0");
  KelvinVoigtProblem<dim> problem(model, material, options);
  return problem.run(out, record_field);
}

template RunReport simulate<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&, bool);
template RunReport simulate<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&, bool);

} // namespace vtb::fem
