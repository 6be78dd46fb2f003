// The Kelvin-Voigt reference distributed over MPI ranks (mpirun -np N): the same equations,
// schemes and lifting as kelvin_voigt.cc, on a parallel::fullydistributed::Triangulation (the
// distributed triangulation that takes simplices) with Trilinos matrices and vectors and a
// Trilinos direct solver. Every rank ends with the same trajectory (sums over ranks).
#include "vtb/core/solver_names.hh"
#include "vtb/fem/kelvin_voigt.hh"

#include "grid.hh"
#include "time_loop.hh"
#include "time_scheme.hh"

#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/tria_description.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <Eigen/Dense>

#include <chrono>
#include <cstdlib>

namespace vtb::fem {
namespace {

using namespace dealii;
using Vec_t = TrilinosWrappers::MPI::Vector;
using Mat_t = TrilinosWrappers::SparseMatrix;

template <int dim> class DistributedProblem {
public:
  DistributedProblem(const Problem<dim>& model, const MaterialDesc& mat, const FemOptions& o)
      : m_model(model), m_mat(mat), m_opt(o), m_scheme(o.scheme, o.static_solve, o.dt), m_comm(MPI_COMM_WORLD),
        m_tria(m_comm), m_fe(FE_SimplexP<dim>(o.degree), dim), m_mapping(FE_SimplexP<dim>(1)), m_dofs(m_tria),
        m_solver(m_control) {}

  RunReport run(Trajectory<dim>& out, bool record_field) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    RunReport rep;
    rep.solver = solvers::kFem;
    rep.dim = dim;
    rep.dt = m_opt.dt;
    rep.duration = m_model.duration;
    rep.nodes = m_model.num_nodes();
    setup();
    assemble();
    initial_state();
    rep.precompute_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    rep.extra = {{"cells", static_cast<double>(m_tria.n_global_active_cells())},
                 {"dofs", static_cast<double>(m_dofs.n_dofs())},
                 {"degree", static_cast<double>(m_opt.degree)},
                 {"refinements", static_cast<double>(m_opt.refinements)},
                 {"mpi_ranks", static_cast<double>(Utilities::MPI::n_mpi_processes(m_comm))}};
    march(
        m_scheme, m_model.duration, m_model.output_interval, rep, [&](double t) { step(t); },
        [&] { return std::isfinite(m_u.l2_norm()); }, [&](double t) { record(t, out, record_field); },
        [&](std::span<const double> times) { interpolate_last_step(out, times); });
    rep.max_strain = m_max_strain;
    return rep;
  }

private:
  void setup() {
    // The serial triangulation (identical on every rank), partitioned, then distributed.
    Triangulation<dim> serial;
    make_triangulation(m_model, m_opt.refinements, serial, m_loads_of_id);
    GridTools::partition_triangulation(Utilities::MPI::n_mpi_processes(m_comm), serial);
    m_tria.create_triangulation(
        TriangulationDescription::Utilities::create_description_from_triangulation(serial, m_comm));
    m_dofs.distribute_dofs(m_fe);
    m_owned = m_dofs.locally_owned_dofs();
    DoFTools::extract_locally_relevant_dofs(m_dofs, m_relevant);

    // Support points, components and the dofs of the scene's nodes (for the dofs this rank sees).
    const auto& unit = m_fe.get_unit_support_points();
    FEValues<dim> fev(m_mapping, m_fe, Quadrature<dim>(unit), update_quadrature_points);
    std::vector<types::global_dof_index> local(m_fe.n_dofs_per_cell());
    std::map<std::vector<double>, int> node_of_point;
    for (int i = 0; i < m_model.num_nodes(); ++i) {
      const Point<dim> p = to_point<dim>(m_model.mesh.points.col(i));
      node_of_point[std::vector<double>(p.begin_raw(), p.end_raw())] = i;
    }
    m_node.assign(static_cast<std::size_t>(m_model.num_nodes()) * dim, numbers::invalid_dof_index);
    for (const auto& cell : m_dofs.active_cell_iterators()) {
      if (!cell->is_locally_owned()) continue;
      fev.reinit(cell);
      cell->get_dof_indices(local);
      for (unsigned int i = 0; i < local.size(); ++i) {
        const Point<dim> p = fev.quadrature_point(i);
        m_point[local[i]] = p;
        m_comp[local[i]] = static_cast<int>(m_fe.system_to_component_index(i).first);
        const auto it = node_of_point.find(std::vector<double>(p.begin_raw(), p.end_raw()));
        if (it != node_of_point.end()) m_node[static_cast<std::size_t>(it->second) * dim + m_comp[local[i]]] = local[i];
      }
    }
    // Prescribed dofs by the same rules as the serial solver.
    const double grow = 1e-9 * bounding_diagonal(m_model.mesh), tol = 1e-10 * bounding_diagonal(m_model.mesh);
    std::map<types::global_dof_index, int> node_dofs; // dof -> node, for node-based supports
    for (std::size_t k = 0; k < m_node.size(); ++k)
      if (m_node[k] != numbers::invalid_dof_index) node_dofs[m_node[k]] = static_cast<int>(k / dim);
    for (const auto& [dof, p] : m_point) {
      for (std::size_t s = 0; s < m_model.supports.size(); ++s) {
        const auto& sup = m_model.supports[s];
        bool in = false;
        if (sup.box) {
          in = true;
          for (int a = 0; a < dim; ++a) in = in && p[a] >= sup.box->min[a] - grow && p[a] <= sup.box->max[a] + grow;
        } else {
          const auto nd = node_dofs.find(dof);
          if (nd != node_dofs.end()) in = std::binary_search(sup.nodes.begin(), sup.nodes.end(), nd->second);
          for (const auto& f : sup.facets)
            if (!in) in = on_facet<dim>(m_model.mesh, p, f, tol);
        }
        if (in) m_support_of[dof] = static_cast<int>(s);
      }
    }
    m_constraints.reinit(m_relevant);
    for (const auto& [dof, s] : m_support_of) m_constraints.add_line(dof);
    m_constraints.close();

    DynamicSparsityPattern dsp(m_relevant);
    DoFTools::make_sparsity_pattern(m_dofs, dsp, AffineConstraints<double>(), true);
    SparsityTools::distribute_sparsity_pattern(dsp, m_owned, m_comm, m_relevant);
    for (auto* A : {&m_K, &m_M, &m_C, &m_A, &m_A0, &m_M0}) A->reinit(m_owned, m_owned, dsp, m_comm);
    for (auto* v : {&m_u, &m_v, &m_a, &m_f, &m_rhs, &m_tmp, &m_ubar, &m_delta, &m_da, &m_dv})
      v->reinit(m_owned, m_comm);
  }

  /// K, M, C and the scheme's matrix A; A0 and M0 with the prescribed rows and columns
  /// eliminated (identity-like diagonal), for the lifted solves.
  void assemble() {
    const double ck = m_scheme.ck(), cm = m_scheme.cm(), cc = m_scheme.cc();
    const QGaussSimplex<dim> quad(static_cast<unsigned int>(m_opt.degree + 1));
    FEValues<dim> fev(m_mapping, m_fe, quad, update_values | update_gradients | update_JxW_values);
    const unsigned int nd = m_fe.n_dofs_per_cell();
    FullMatrix<double> k(nd, nd), m(nd, nd), c(nd, nd), a(nd, nd);
    std::vector<types::global_dof_index> local(nd);
    const AffineConstraints<double> none;
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
    for (auto* A : {&m_K, &m_M, &m_C, &m_A, &m_A0, &m_M0}) A->compress(VectorOperation::add);
    m_solver.initialize(m_A0);
  }

  double prescribed(types::global_dof_index d, double t) const {
    const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of.at(d))];
    return s.driven ? ramp_factor(t, s.start, s.ramp) * s.displacement[m_comp.at(d)] : 0.0;
  }

  void load_vector(double t, Vec_t& f) {
    f = 0;
    std::vector<Tensor<1, dim>> traction(m_loads_of_id.size());
    for (std::size_t id = 1; id < m_loads_of_id.size(); ++id)
      for (int l : m_loads_of_id[id]) {
        const auto& load = m_model.loads[static_cast<std::size_t>(l)];
        double measure = 0;
        for (const auto& fc : load.facets) measure += facet_measure(m_model.mesh, fc);
        for (int a = 0; a < dim; ++a)
          traction[id][a] += ramp_factor(t, load.start, load.ramp) * load.total[a] / measure;
      }
    const QGaussSimplex<dim - 1> fquad(static_cast<unsigned int>(m_opt.degree + 1));
    FEFaceValues<dim> fv(m_mapping, m_fe, fquad, update_values | update_JxW_values);
    std::vector<types::global_dof_index> local(m_fe.n_dofs_per_cell());
    Vector<double> cell_f(m_fe.n_dofs_per_cell());
    const AffineConstraints<double> none;
    for (const auto& cell : m_dofs.active_cell_iterators()) {
      if (!cell->is_locally_owned()) continue;
      cell_f = 0;
      bool any = false;
      for (const unsigned int face : cell->face_indices()) {
        const auto id = cell->face(face)->boundary_id();
        if (!cell->face(face)->at_boundary() || id == 0 || id >= m_loads_of_id.size()) continue;
        fv.reinit(cell, face);
        any = true;
        for (unsigned int q = 0; q < fquad.size(); ++q)
          for (unsigned int i = 0; i < cell_f.size(); ++i)
            cell_f[i] += traction[id][m_fe.system_to_component_index(i).first] * fv.shape_value(i, q) * fv.JxW(q);
      }
      if (any) {
        cell->get_dof_indices(local);
        none.distribute_local_to_global(cell_f, local, f);
      }
    }
    for (const auto& load : m_model.loads) {
      if (!load.facets.empty()) continue;
      const double s = ramp_factor(t, load.start, load.ramp);
      for (std::size_t k = 0; k < load.nodes.size(); ++k)
        for (int a = 0; a < dim; ++a) {
          const auto d = m_node[static_cast<std::size_t>(load.nodes[k]) * dim + a];
          if (d != numbers::invalid_dof_index && m_owned.is_element(d))
            f[d] += s * load.force(a, static_cast<Eigen::Index>(k));
        }
    }
    f.compress(VectorOperation::add);
  }

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
      for (int a = 0; a < dim; ++a) x[a] = m_point.at(d)[a];
      x[dim] = 1;
      m_v[d] = affine.row(m_comp.at(d)).dot(x);
      if (m_support_of.count(d)) {
        const auto& s = m_model.supports[static_cast<std::size_t>(m_support_of.at(d))];
        m_u[d] = prescribed(d, 0.0);
        m_v[d] = s.driven ? ramp_rate(0.0, s.start, s.ramp) * s.displacement[m_comp.at(d)] : 0.0;
      }
    }
    m_u.compress(VectorOperation::insert);
    m_v.compress(VectorOperation::insert);
    if (m_scheme.newmark_family) {
      load_vector(-1e-12 * m_opt.dt, m_rhs); // the loads just before t = 0 (see kelvin_voigt.cc)
      m_C.vmult(m_tmp, m_v);
      m_rhs -= m_tmp;
      m_K.vmult(m_tmp, m_u);
      m_rhs -= m_tmp;
      zero_prescribed(m_rhs);
      SolverControl control(1, 0);
      TrilinosWrappers::SolverDirect msolve(control);
      msolve.initialize(m_M0);
      msolve.solve(m_a, m_rhs);
    }
  }

  void zero_prescribed(Vec_t& v) {
    for (const auto& [d, s] : m_support_of)
      if (m_owned.is_element(d)) v[d] = 0;
    v.compress(VectorOperation::insert);
  }

  void step(double t_new) {
    load_vector(m_scheme.load_time(t_new), m_rhs);
    m_scheme.add_history(m_M, m_C, m_K, m_u, m_v, m_a, m_da, m_dv, m_tmp, m_rhs);
    m_ubar = m_u;
    for (const auto& [d, s] : m_support_of)
      if (m_owned.is_element(d)) m_ubar[d] = prescribed(d, t_new);
    m_ubar.compress(VectorOperation::insert);
    m_A.vmult(m_tmp, m_ubar);
    m_rhs -= m_tmp;
    zero_prescribed(m_rhs);
    m_solver.solve(m_delta, m_rhs);
    m_ubar += m_delta;
    if (!m_opt.static_solve)
      for (const auto d : m_owned) {
        const auto it = m_support_of.find(d);
        if (m_scheme.newmark_family && it != m_support_of.end()) { // the known motion (see kelvin_voigt.cc)
          const auto& s = m_model.supports[static_cast<std::size_t>(it->second)];
          m_v[d] = s.driven ? ramp_rate(t_new, s.start, s.ramp) * s.displacement[m_comp.at(d)] : 0.0;
          m_a[d] = 0;
          continue;
        }
        double v = m_v[d], a = m_a[d];
        m_scheme.update(m_ubar[d], m_u[d], m_da[d], m_dv[d], v, a);
        m_v[d] = v;
        m_a[d] = a;
      }
    m_a.compress(VectorOperation::insert);
    m_v.compress(VectorOperation::insert);
    m_u = m_ubar;
  }

  /// Probes, reactions and the nodal field, summed over the ranks (each owns its dofs).
  void record(double t, Trajectory<dim>& out, bool record_field) {
    out.t.push_back(t);
    std::vector<double> field(static_cast<std::size_t>(m_model.num_nodes()) * dim, 0.0);
    for (std::size_t k = 0; k < field.size(); ++k)
      if (m_node[k] != numbers::invalid_dof_index && m_owned.is_element(m_node[k])) field[k] = m_u[m_node[k]];
    Utilities::MPI::sum(field, m_comm, field);
    std::vector<Vec<dim>> pu;
    for (const auto& [name, node] : m_model.probes)
      pu.push_back(Eigen::Map<const Vec<dim>>(field.data() + static_cast<std::size_t>(node) * dim));
    out.probe_u.push_back(pu);
    load_vector(t, m_f);
    m_K.vmult(m_rhs, m_u);
    if (!m_opt.static_solve) {
      m_C.vmult(m_tmp, m_v);
      m_rhs += m_tmp;
      m_M.vmult(m_tmp, m_a);
      m_rhs += m_tmp;
    }
    m_rhs -= m_f;
    std::vector<double> reac(m_model.supports.size() * dim, 0.0);
    for (const auto& [d, s] : m_support_of)
      if (m_owned.is_element(d))
        reac[static_cast<std::size_t>(s) * dim + static_cast<std::size_t>(m_comp.at(d))] += m_rhs[d];
    Utilities::MPI::sum(reac, m_comm, reac);
    std::vector<Vec<dim>> r(m_model.supports.size());
    for (std::size_t s = 0; s < r.size(); ++s) r[s] = Eigen::Map<const Vec<dim>>(reac.data() + s * dim);
    out.reaction.push_back(r);
    if (record_field) out.field.push_back(Eigen::Map<const Nodal<dim>>(field.data(), dim, m_model.num_nodes()));
    // Largest principal strain magnitude at the centres of this rank's cells, max over ranks.
    Vec_t ghosted(m_owned, m_relevant, m_comm);
    ghosted = m_u;
    m_max_strain =
        std::max(m_max_strain, Utilities::MPI::max(max_principal_strain(m_mapping, m_fe, m_dofs, ghosted), m_comm));
  }

  double m_max_strain = 0;

  const Problem<dim>& m_model;
  const MaterialDesc& m_mat;
  const FemOptions m_opt;
  const TimeScheme m_scheme;
  MPI_Comm m_comm;
  parallel::fullydistributed::Triangulation<dim> m_tria;
  FESystem<dim> m_fe;
  MappingFE<dim> m_mapping;
  DoFHandler<dim> m_dofs;
  IndexSet m_owned, m_relevant;
  std::vector<std::vector<int>> m_loads_of_id;
  std::map<types::global_dof_index, Point<dim>> m_point;
  std::map<types::global_dof_index, int> m_comp, m_support_of;
  std::vector<types::global_dof_index> m_node; ///< [node * dim + component], invalid if not seen here
  AffineConstraints<double> m_constraints;
  Mat_t m_K, m_M, m_C, m_A, m_A0, m_M0;
  SolverControl m_control{1, 0};
  TrilinosWrappers::SolverDirect m_solver;
  Vec_t m_u, m_v, m_a, m_f, m_rhs, m_tmp, m_ubar, m_delta, m_da, m_dv;
};

} // namespace

struct MpiScope::Impl {
  std::unique_ptr<Utilities::MPI::MPI_InitFinalize> init;
};

MpiScope::MpiScope(int& argc, char**& argv) : m_impl(std::make_unique<Impl>()) {
  // Only under a launcher: a plain run never touches MPI.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE"))
    m_impl->init = std::make_unique<Utilities::MPI::MPI_InitFinalize>(argc, argv, 1);
}
MpiScope::~MpiScope() = default;

int mpi_size() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  return initialized ? static_cast<int>(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) : 1;
}
int mpi_rank() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  return initialized ? static_cast<int>(Utilities::MPI::this_mpi_process(MPI_COMM_WORLD)) : 0;
}

template <int dim>
RunReport simulate_distributed(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                               Trajectory<dim>& out, bool record_field) {
  DistributedProblem<dim> problem(model, material, options);
  return problem.run(out, record_field);
}

template RunReport simulate_distributed<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&,
                                           bool);
template RunReport simulate_distributed<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&,
                                           bool);

} // namespace vtb::fem
