#include "vtb/solvers/filtered.hh"

#include "vtb/problem/solver_names.hh"

#include "vtb/linalg/selected_inverse.hh"
#include "vtb/springs/force_jacobian.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace vtb {

template <int dim> Eigen::SparseMatrix<double> filter_system_matrix(const Model<dim>& model, double dt) {
  const auto& net = model.net;
  const int nf = static_cast<int>(model.free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(nf + 4 * net.num_springs()));
  for (int a = 0; a < nf; ++a) {
    const int i = model.free_nodes[static_cast<std::size_t>(a)];
    trip.emplace_back(a, a, net.mass[i] * (1.0 + dt * net.mass_damping));
  }
  // The shared assembly at rest, each block taken by its trace: a spring's true Jacobian at
  // rest is k n n^T (and c n n^T), whose trace is k (c), so H is the edge-weighted Laplacian
  // M + dt C_L + dt^2 K_L of the paper, the isotropic part of the true M + dt D + dt^2 K.
  const Nodal<dim> rest = Nodal<dim>::Zero(dim, net.num_nodes());
  for_each_jacobian_block(net, rest, false, [&](int, int i, int j, double sign, const Mat<dim>& K, const Mat<dim>& D) {
    const int a = model.free_index[static_cast<std::size_t>(i)], b = model.free_index[static_cast<std::size_t>(j)];
    if (a >= 0 && b >= 0) trip.emplace_back(a, b, -sign * (dt * D.trace() + dt * dt * K.trace()));
  });
  // The volume term's blocks at rest by their traces too: k_c g_a . g_b, a Gram matrix of the
  // cell's gradients, so H stays positive definite.
  for_each_cell_block(net.volume, net.rest, rest, false,
                      [&](int c, int x, int y, const Mat<dim>& K, const Mat<dim>& D) {
                        const auto& cell = net.volume.cell[static_cast<std::size_t>(c)];
                        const int a = model.free_index[static_cast<std::size_t>(cell[x])];
                        const int b = model.free_index[static_cast<std::size_t>(cell[y])];
                        if (a >= 0 && b >= 0) trip.emplace_back(a, b, -(dt * D.trace() + dt * dt * K.trace()));
                      });
  Eigen::SparseMatrix<double> H(nf, nf);
  H.setFromTriplets(trip.begin(), trip.end());
  return H;
}

template <int dim> Eigen::MatrixXd filter_matrix_full(const Model<dim>& model, double dt) {
  const Eigen::MatrixXd H(filter_system_matrix(model, dt));
  const Eigen::Index nf = H.rows();
  Eigen::VectorXd m(nf);
  for (Eigen::Index a = 0; a < nf; ++a) m[a] = model.net.mass[model.free_nodes[static_cast<std::size_t>(a)]];
  Eigen::MatrixXd W = Eigen::MatrixXd(m.asDiagonal());
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  llt.solveInPlace(W);
  return W;
}

template <int dim>
Eigen::SparseMatrix<double, Eigen::RowMajor> filter_matrix_neighbors(const Model<dim>& model, double dt) {
  Eigen::SparseMatrix<double> Z = selected_inverse(filter_system_matrix(model, dt));
  // W_ab = Z_ab m_b: scale column b.
  for (int b = 0; b < Z.outerSize(); ++b)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, b); it; ++it)
      it.valueRef() *= model.net.mass[model.free_nodes[static_cast<std::size_t>(b)]];
  return Eigen::SparseMatrix<double, Eigen::RowMajor>(Z);
}

template <int dim>
FilteredImplicit<dim>::FilteredImplicit(const Model<dim>& model, const IntegratorOptions& o)
    : Integrator<dim>(o.dt), m_model(model), m_filter(chosen_filter(model, o.filter)),
      m_full(m_filter == solvers::kFilterFull || m_filter == solvers::kFilterMultigrid),
      m_correct(o.momentum_correction && !model.has_constraints()), m_strain_limit(o.strain_limit) {
  if (std::find(solvers::kFilters.begin(), solvers::kFilters.end(), m_filter) == solvers::kFilters.end())
    throw InputError("[solver].filter = \"" + o.filter + "\": must be " + solvers::kFilterAuto +
                     ", neighbors, full, tensor, multigrid or tensor-multigrid");
  const Eigen::Index n = model.num_nodes();
  const auto nf = static_cast<Eigen::Index>(model.free_nodes.size());
  if (m_filter == solvers::kFilterTensor || m_filter == solvers::kFilterTensorMultigrid) {
    if (!model.net.volume.empty())
      throw InputError("[solver].filter = \"" + m_filter + "\": the tensor filter does not take springs = \"" +
                       model.net.calibration +
                       "\"'s cell term; use auto, full, "
                       "multigrid or neighbors");
    const bool multigrid = m_filter == solvers::kFilterTensorMultigrid;
    m_tensor = std::make_unique<TensorFilter<dim>>(model, o.dt, multigrid);
    // Its fallback: implicit Euler with the current Jacobian, by the linear solver implicit
    // Euler itself runs (`linear_solver`, auto by default: the refactorised LDL^T in 2D, CG in
    // 3D, where the factor cost 1.5-1.6x the CG on held-out blocks: docs/method.md).
    IntegratorOptions ie = o;
    ie.kind = solvers::kImplicitEuler;
    m_fallback_ie = make_integrator(model, ie);
  }
  if (m_filter == solvers::kFilterMultigrid) {
    m_mg = std::make_unique<SymmetricMultigrid<dim>>(filter_system_matrix(model, o.dt));
    m_rhs.resize(dim, nf);
    m_mg_units = std::make_unique<CouplingSet<dim>>(model.free_index);
    m_mg_in = Nodal<dim>::Zero(dim, nf);
    m_mg_out = Nodal<dim>::Zero(dim, nf);
  } else if (m_full) {
    OrderedLDLT factor(filter_system_matrix(model, o.dt));
    if (!factor.factorize()) throw std::runtime_error("filtered: H is not positive definite");
    m_h = std::make_unique<NodalSolve>(factor);
    m_node_of_row.resize(static_cast<std::size_t>(nf));
    m_row_of_node.assign(static_cast<std::size_t>(n), -1);
    for (int a = 0; a < static_cast<int>(nf); ++a) {
      const int node = model.free_nodes[static_cast<std::size_t>(a)];
      m_node_of_row[static_cast<std::size_t>(factor.ordered(a))] = node;
      m_row_of_node[static_cast<std::size_t>(node)] = factor.ordered(a);
    }
    m_rhs.resize(dim, nf);
    m_couplings = std::make_unique<ScalarCouplings<dim>>(*m_h, nf);
  } else if (!m_tensor) {
    m_sparse = filter_matrix_neighbors(model, o.dt);
  }
  // The couplings' units, by the slots of the system that solves them: free nodes (tensor) or
  // the factor's rows (full).
  if (m_tensor) m_units = std::make_unique<CouplingSet<dim>>(model.free_index);
  if (m_h) m_units = std::make_unique<CouplingSet<dim>>(m_row_of_node);
  m_force.resize(dim, n);
  m_acc.resize(dim, nf);
  m_dv.resize(dim, nf);
}

namespace {

/// v_i += scale dv_k and then u_i += dt v_i for node i = node[k], k < n. Through raw pointers:
/// Eigen's columns of s.v and s.u reloaded their data pointers from the State after every
/// store (a store might have changed them), and the loop waited on those loads (2.6 us of the
/// 517-node tensor step, docs/performance.md).
template <int dim>
void advance(State<dim>& s, Eigen::Index n, const int* node, const Nodal<dim>& dv, double scale, double dt) {
  double* __restrict v = s.v.data();
  double* __restrict u = s.u.data();
  const double* __restrict d = dv.data();
  for (Eigen::Index k = 0; k < n; ++k) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(node[k]) * dim;
    for (int p = 0; p < dim; ++p) {
      v[i + p] += scale * d[k * dim + p];
      u[i + p] += dt * v[i + p];
    }
  }
}

} // namespace

template <int dim> void FilteredImplicit<dim>::step(State<dim>& s) {
  const double dt = this->dt();
  const auto& net = m_model.net;
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<Eigen::Index>(free.size());

  // F_node: Voigt forces with the extra k dt axial term, plus loads and mass damping; in 2D
  // with the tensor filter, its springs' turns in the same pass (its rotations read them), so
  // there the forces come before its check (and go unused on a step it hands to implicit
  // Euler: about 2 % of that step on the plate), elsewhere after it.
  const bool turns = dim == 2 && m_tensor;
  const auto node_forces = [&] {
    m_model.external_forces(s.t + dt, m_force);
    if (s.applied.cols() == m_force.cols()) m_force += s.applied;
    if constexpr (dim == 2) {
      if (turns) {
        add_internal_forces_and_turns(net, s.u, s.v, m_force, dt, m_tensor->turns());
        return;
      }
    }
    add_internal_forces(net, s.u, s.v, m_force, dt);
  };
  if (turns) node_forces();

  // The tensor filter, lag-free about its reference shape while the distortion from it is
  // trusted (kTrustedMismatch); past that the reference moves to the current shape
  // (relinearize), its refactorisation spread over the next steps, which the H in use serves
  // meanwhile, unless the distortion passes kHardMismatch first (then at once: docs/method.md).
  // Implicit Euler stays the safety net for a state with no finite mismatch, which its own
  // step and the run's watch then meet.
  if (m_tensor) {
    double mismatch = turns ? m_tensor->prepare_turned(s.u) : m_tensor->prepare(s.u);
    if (std::isfinite(mismatch) && mismatch > TensorFilter<dim>::kTrustedMismatch) {
      if (!m_tensor->relinearizing()) m_tensor->relinearize(s.u, false);
      if (mismatch > TensorFilter<dim>::kHardMismatch) {
        m_tensor->finish_refresh();
        mismatch = m_tensor->prepare(s.u);
      }
    }
    m_fallback = !(mismatch <= TensorFilter<dim>::kHardMismatch);
    m_mismatch = mismatch;
    m_fallback_steps += m_fallback;
    if (m_fallback) {
      m_fallback_ie->step(s);
      if (m_strain_limit > 0) limit_strain(s);
      return;
    }
  }
  if (!turns) node_forces();

  // The couplings' implicit part, for the filters with a factor (tensor, full): their force's
  // -dt K v term here, their units' c w w^T joining H through Woodbury's identity.
  if (m_units) {
    if (s.applied_stiffness.size() == m_force.cols() || s.applied_damping.size() == m_force.cols()) {
      m_units->gather(s, dt);
      m_units->add_force_correction(s.v, dt, m_force);
    } else if (m_units->units() > 0) {
      m_units->set(Eigen::VectorXd(), Eigen::VectorXd(), Eigen::VectorXi(), dt);
    }
  }
  // The accelerations M^-1 F: what the neighbour filter multiplies and the momentum correction
  // compares with; the full and tensor filters solve with F itself.
  if ((!m_full && !m_tensor) || m_correct)
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      m_acc.col(a) = m_force.col(i) / net.mass[i];
    }
  // dv = dt W a.
  if (m_tensor && !m_fallback) {
    m_tensor->solve(m_force, *m_units, dt, m_dv);
    // Toward implicit Euler's step where a cover or the V-cycle makes H depart from the
    // warped rest Jacobian (TensorFilter::correct).
    m_tensor->correct(s.u, s.v, m_force, *m_units, dt, m_dv);
    m_tensor->advance_refresh(m_mismatch); // this step's part of a refactorisation under way
  } else if (m_mg) {
    // The couplings' units, for their local models only (coupling_compliance).
    if (s.applied_stiffness.size() == m_force.cols() || s.applied_damping.size() == m_force.cols())
      m_mg_units->gather(s, dt);
    // H^-1 F_node by one V-cycle, in the free nodes' order.
    for (Eigen::Index a = 0; a < nf; ++a) m_rhs.col(a) = m_force.col(free[static_cast<std::size_t>(a)]);
    m_mg->apply(m_rhs, m_dv);
    m_dv *= dt;
  } else if (m_h) {
    m_couplings->set(*m_units);
    // W a = H^-1 M a = H^-1 F_node.
    m_h->solve_gathered<dim>(m_force, m_node_of_row.data(), m_rhs);
    m_couplings->correct(m_rhs);
    if (!m_correct) { // nothing reads dv but the update: apply it in the factor's order
      advance<dim>(s, nf, m_node_of_row.data(), m_rhs, dt, dt);
      finish_step(s);
      return;
    }
    for (Eigen::Index r = 0; r < nf; ++r)
      m_dv.col(m_model.free_index[static_cast<std::size_t>(m_node_of_row[static_cast<std::size_t>(r)])]) =
          dt * m_rhs.col(r);
  } else {
    const int* ptr = m_sparse.outerIndexPtr();
    const int* col = m_sparse.innerIndexPtr();
    const double* val = m_sparse.valuePtr();
    for (Eigen::Index a = 0; a < nf; ++a) {
      Vec<dim> acc = Vec<dim>::Zero();
      for (int p = ptr[a]; p < ptr[a + 1]; ++p) acc += val[p] * m_acc.col(col[p]);
      m_dv.col(a) = dt * acc;
    }
  }
  if (m_correct) correct_momentum(s);
  advance<dim>(s, nf, free.data(), m_dv, 1.0, dt);
  finish_step(s);
}

template <int dim>
bool FilteredImplicit<dim>::coupling_compliance(int group, Eigen::Matrix<double, dim, dim>& out) const {
  if (m_mg_units) {
    const int u = m_mg_units->unit_of_group(group);
    if (u < 0) return false;
    out = this->dt() * this->dt() * multigrid_response(u) * Eigen::Matrix<double, dim, dim>::Identity();
    return true;
  }
  if (!m_units || m_fallback) return false;
  const int u = m_units->unit_of_group(group);
  if (u < 0) return false;
  const double dt2 = this->dt() * this->dt();
  if (m_tensor) {
    out = dt2 * m_tensor->unit_response(u);
    return true;
  }
  if (m_couplings) {
    out = dt2 * m_couplings->unit_response(u) * Eigen::Matrix<double, dim, dim>::Identity();
    return true;
  }
  return false;
}

template <int dim> double FilteredImplicit<dim>::multigrid_response(int u) const {
  const CouplingSet<dim>& units = *m_mg_units;
  MgResponse& r = m_mg_response[static_cast<std::size_t>(u)];
  // Kept while the nodes are the same and the weights (which sum to 1) moved by at most
  // kResponseTolerance in sum: w^T A w then moves by about twice that, relative.
  bool same = r.size == units.size(u);
  double moved = 0;
  for (int p = 0; p < units.size(u) && same; ++p) {
    same = r.node[static_cast<std::size_t>(p)] == units.node(u, p);
    moved += std::abs(r.weight[static_cast<std::size_t>(p)] - units.weight(u, p));
  }
  if (same && moved <= kResponseTolerance) return r.value;
  // One V-cycle on the unit's weights (one axis: the scalar filter is the same on each).
  m_mg_in.setZero();
  for (int p = 0; p < units.size(u); ++p) m_mg_in(0, units.slot(u, p)) = units.weight(u, p);
  m_mg->apply(m_mg_in, m_mg_out);
  r.value = 0;
  r.size = units.size(u);
  for (int p = 0; p < units.size(u); ++p) {
    r.value += units.weight(u, p) * m_mg_out(0, units.slot(u, p));
    r.node[static_cast<std::size_t>(p)] = units.node(u, p);
    r.weight[static_cast<std::size_t>(p)] = units.weight(u, p);
  }
  return r.value;
}

/// The step's end: the time, the supports' prescribed motion, the strain limit.
template <int dim> void FilteredImplicit<dim>::finish_step(State<dim>& s) {
  s.t += this->dt();
  m_model.apply_constraints(s.t, s.u, s.v);
  if (m_strain_limit > 0) limit_strain(s);
}

template <int dim> void FilteredImplicit<dim>::correct_momentum(const State<dim>& s) {
  // The unfiltered impulse dt F carries exactly the right linear and angular impulse
  // (internal forces are central pairs); remove what the filter changed.
  const auto& net = m_model.net;
  const auto& free = m_model.free_nodes;
  const auto nf = static_cast<Eigen::Index>(free.size());
  const double dt = this->dt();
  double mtot = 0;
  Vec<dim> xg = Vec<dim>::Zero(), dp = Vec<dim>::Zero();
  for (Eigen::Index a = 0; a < nf; ++a) {
    const int i = free[static_cast<std::size_t>(a)];
    const double m = net.mass[i];
    mtot += m;
    xg += m * (net.rest.col(i) + s.u.col(i));
    dp += m * (m_dv.col(a) - dt * m_acc.col(a));
  }
  xg /= mtot;
  m_dv.colwise() -= dp / mtot;
  if constexpr (dim == 2) {
    double dl = 0, inertia = 0;
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      const Vec<2> r = net.rest.col(i) + s.u.col(i) - xg;
      const Vec<2> e = m_dv.col(a) - dt * m_acc.col(a);
      dl += net.mass[i] * (r.x() * e.y() - r.y() * e.x());
      inertia += net.mass[i] * r.squaredNorm();
    }
    const double w = dl / inertia;
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      const Vec<2> r = net.rest.col(i) + s.u.col(i) - xg;
      m_dv.col(a) -= Vec<2>(-w * r.y(), w * r.x());
    }
  } else {
    Eigen::Vector3d dl = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      const Eigen::Vector3d r = net.rest.col(i) + s.u.col(i) - xg;
      const Eigen::Vector3d e = m_dv.col(a) - dt * m_acc.col(a);
      dl += net.mass[i] * r.cross(e);
      inertia += net.mass[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    }
    const Eigen::Vector3d w = inertia.ldlt().solve(dl);
    for (Eigen::Index a = 0; a < nf; ++a) {
      const int i = free[static_cast<std::size_t>(a)];
      const Eigen::Vector3d r = net.rest.col(i) + s.u.col(i) - xg;
      m_dv.col(a) -= w.cross(r);
    }
  }
}

template <int dim> void FilteredImplicit<dim>::limit_strain(State<dim>& s) const {
  const auto& net = m_model.net;
  const double inv_dt = 1.0 / this->dt();
  const double limit = 1.0 + m_strain_limit;
  for (int sp = 0; sp < net.num_springs(); ++sp) {
    const int i = net.edge[static_cast<std::size_t>(sp)][0], j = net.edge[static_cast<std::size_t>(sp)][1];
    const double wi = m_model.constrained[static_cast<std::size_t>(i)] ? 0.0 : 1.0 / net.mass[i];
    const double wj = m_model.constrained[static_cast<std::size_t>(j)] ? 0.0 : 1.0 / net.mass[j];
    if (wi + wj == 0) continue;
    const Vec<dim> d = net.rest.col(j) + s.u.col(j) - net.rest.col(i) - s.u.col(i);
    const double l = d.norm();
    const double target = limit * net.rest_length[sp];
    if (!(l > target)) continue;
    const Vec<dim> shift = (l - target) / (l * (wi + wj)) * d; // total shortening along d
    const Vec<dim> di = wi * shift, dj = -wj * shift;
    s.u.col(i) += di;
    s.v.col(i) += inv_dt * di;
    s.u.col(j) += dj;
    s.v.col(j) += inv_dt * dj;
  }
}

template class FilteredImplicit<2>;
template class FilteredImplicit<3>;
template Eigen::SparseMatrix<double> filter_system_matrix<2>(const Model<2>&, double);
template Eigen::SparseMatrix<double> filter_system_matrix<3>(const Model<3>&, double);
template Eigen::MatrixXd filter_matrix_full<2>(const Model<2>&, double);
template Eigen::MatrixXd filter_matrix_full<3>(const Model<3>&, double);
template Eigen::SparseMatrix<double, Eigen::RowMajor> filter_matrix_neighbors<2>(const Model<2>&, double);
template Eigen::SparseMatrix<double, Eigen::RowMajor> filter_matrix_neighbors<3>(const Model<3>&, double);

} // namespace vtb
