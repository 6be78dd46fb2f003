#include "vtb/stepper/live_sim.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"
#include "vtb/solvers/filter_pick.hh"
#include "vtb/solvers/filtered.hh"

#include "vtb/base/input_error.hh"
#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/simulation.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace vtb {

template <int dim>
LiveSim<dim>::LiveSim(const Scene& scene, Mesh<dim> mesh, SimControls controls, Yardstick yardstick)
    : m_scene(scene), m_mesh(std::move(mesh)), m_yardstick(std::move(yardstick)), m_controls(std::move(controls)),
      m_grab_radius((scene.haptics ? *scene.haptics : HapticsDesc{}).tip_radius_for(dim)),
      m_on_boundary(static_cast<std::size_t>(m_mesh.num_nodes()), 0) {
  for (const auto& f : boundary_facets(m_mesh))
    for (int v : f) m_on_boundary[static_cast<std::size_t>(v)] = 1;
  rebuild();
  // A coupling a few times stiffer than a typical spring pulls visibly without dominating
  // the body; the panel changes it.
  const auto& k = m_model->net.stiffness;
  coupling_stiffness = k.size() ? 4.0 * k.mean() : 100.0;
}

template <int dim> void LiveSim<dim>::rebuild() {
  const auto names = interactive_solvers();
  if (std::find(names.begin(), names.end(), m_controls.solver) == names.end())
    throw InputError("vtb view: solver \"" + m_controls.solver + "\" cannot run interactively (" +
                     solvers::list(solvers::is_stepper) + ")");
  checked_dt(m_controls.dt);
  if (!(m_controls.stiffness_scale > 0)) throw InputError("vtb view: the stiffness scale must be > 0");
  Scene s = m_scene;
  s.material.young_modulus *= m_controls.stiffness_scale;
  s.solver.springs = m_controls.springs;
  // The springs' error on the scene's loads does not change with the stiffness, dt, the solver
  // or the filter: measured again only when the springs change (about 2 s at 10k nodes).
  const bool same_springs = m_model && m_model->net.calibration_requested == m_controls.springs;
  auto model = std::make_unique<Model<dim>>(build_model<dim>(s, m_mesh, {}, !same_springs, &m_yardstick));
  if (same_springs) {
    model->net.calibration_load_error = m_model->net.calibration_load_error;
    model->net.mesh_fem_load_error = m_model->net.mesh_fem_load_error;
    model->net.calibration_yardstick = m_model->net.calibration_yardstick;
  }
  IntegratorOptions o = integrator_options(s.solver);
  o.kind = m_controls.solver;
  o.filter = m_controls.filter;
  o.dt = m_controls.dt;
  o = with_budget_pick(*model, o);         // auto within [solver].step_budget (filter_pick.hh)
  auto integ = make_integrator(*model, o); // the integrator keeps a reference to *model
  m_stats.step_budget_us = o.step_budget * 1e6;
  m_stats.steps_over_budget = 0;
  m_stats.filter_reason = o.filter_reason;
  const bool same_size = m_model && m_model->num_nodes() == model->num_nodes();
  const auto* filtered = dynamic_cast<const FilteredImplicit<dim>*>(integ.get());
  m_running_filter = filtered ? filtered->filter() : std::string();
  m_integ = std::move(integ);
  m_model = std::move(model);
  if (!same_size || !m_failure.empty()) {
    restart();
    m_failure.clear();
  }
  if (!same_size) {
    m_state.applied = Nodal<dim>::Zero(dim, m_model->num_nodes());
    m_state.applied_stiffness = Eigen::VectorXd::Zero(m_model->num_nodes());
    m_state.applied_damping = Eigen::VectorXd::Zero(m_model->num_nodes());
    m_state.applied_group = Eigen::VectorXi::Constant(m_model->num_nodes(), -1);
    m_external_force = Nodal<dim>::Zero(dim, m_model->num_nodes());
    m_external_stiffness = Eigen::VectorXd::Zero(m_model->num_nodes());
    m_external_damping = Eigen::VectorXd::Zero(m_model->num_nodes());
  }
  const double tau = m_model->net.stiffness.size() ? m_model->net.damping[0] / m_model->net.stiffness[0] : 0.0;
  m_courant_dt = explicit_critical_dt(max_omega_squared(*m_model, false), tau, m_model->net.mass_damping);
  m_probe_node = m_model->probes.empty() ? -1 : m_model->probes.front().second;
  m_probe_name = m_model->probes.empty() ? "" : m_model->probes.front().first;
}

template <int dim> void LiveSim<dim>::configure(const SimControls& controls) {
  const SimControls old = m_controls;
  m_controls = controls;
  try {
    rebuild();
  } catch (...) {
    m_controls = old;
    throw;
  }
}

template <int dim> void LiveSim<dim>::restart() {
  const State<dim> s0 = initial_state(*m_model);
  m_state.t = s0.t;
  m_state.u = s0.u; // same size: Eigen copies into the storage it has
  m_state.v = s0.v;
}

template <int dim> void LiveSim<dim>::reset() {
  restart();
  m_state.applied.setZero();
  m_state.applied_stiffness.setZero();
  m_state.applied_damping.setZero();
  m_failure.clear();
  m_stats = SimStats{};
  m_trace.clear();
  m_step_count = 0;
}

template <int dim> Vec<dim> LiveSim<dim>::grabbed(int k) const {
  const auto& p = m_pulls[static_cast<std::size_t>(k)];
  Vec<dim> x = Vec<dim>::Zero();
  for (std::size_t q = 0; q < static_cast<std::size_t>(p.count); ++q) x += p.weights[q] * position(p.nodes[q]);
  return x;
}

template <int dim> Vec<dim> LiveSim<dim>::pull_force(int k) const {
  return coupling_stiffness * (m_pulls[static_cast<std::size_t>(k)].target - grabbed(k));
}

template <int dim> void LiveSim<dim>::step_once() {
  using clock = std::chrono::steady_clock;
  m_state.applied = m_external_force;
  m_state.applied_stiffness = m_external_stiffness; // and each pull's spring, for the solvers that take it implicitly
  m_state.applied_damping = m_external_damping;
  m_state.applied_group.setConstant(-1);
  // Each pull's spring on its patch by the weights, and its stiffness as the diagonal bound
  // w_i k per node, not as one group: a drag stretches the tissue far (spring strains of 0.4
  // on a 2 cm box pulled 4 mm), and there the tensor filter with the exact k w w^T let the
  // patch's nodes part in a transient that the diagonal bound holds (docs/viewer.md).
  for (int k = 0; k < m_num_pulls; ++k) {
    const auto& p = m_pulls[static_cast<std::size_t>(k)];
    const Vec<dim> f = pull_force(k);
    for (std::size_t q = 0; q < static_cast<std::size_t>(p.count); ++q) {
      const int node = p.nodes[q];
      m_state.applied.col(node) += p.weights[q] * f;
      m_state.applied_stiffness[node] += p.weights[q] * coupling_stiffness;
    }
  }
  if (m_hook) m_hook->before_step(*m_model, m_state, m_controls.dt);
  const auto a = clock::now();
  m_integ->step(m_state);
  const double us = std::chrono::duration<double, std::micro>(clock::now() - a).count();
  if (m_hook) m_hook->after_step(*m_model, m_state, *m_integ);
  m_step_us[static_cast<std::size_t>(m_step_count % static_cast<int>(m_step_us.size()))] = us;
  if (m_stats.step_budget_us > 0 && us > m_stats.step_budget_us) ++m_stats.steps_over_budget;
  ++m_step_count;
  ++m_stats.steps;
  check(false);
  if (m_probe_node >= 0) {
    m_trace.push(static_cast<float>(m_state.u.col(m_probe_node).norm()));
  }
}

template <int dim> void LiveSim<dim>::check(bool strain_now) {
  const bool finite = m_state.u.allFinite() && m_state.v.allFinite();
  if (finite && !strain_now && m_step_count % kStrainCheckSteps != 0) return;
  const double strain = finite ? max_strain(m_model->net, m_state.u) : INFINITY;
  if (!finite || !(strain <= kRunawayStrain)) {
    std::ostringstream os;
    os << m_controls.solver
       << (m_running_filter.empty() ? "" : " (" + m_running_filter + ")") // what ran, a budget's pick included
       << " went unstable at t = " << m_state.t << " s (dt = " << m_controls.dt
       << " s): " << (finite ? "runaway strain" : "non-finite state");
    m_failure = os.str();
  }
}

template <int dim> void LiveSim<dim>::advance(double sim_seconds, double wall_budget) {
  using clock = std::chrono::steady_clock;
  if (!m_failure.empty()) return;
  const auto start = clock::now();
  long count = static_cast<long>(std::floor(sim_seconds / m_controls.dt + 1e-9));
  if (count == 0) { // a step longer than the frame: once the frames have asked for it
    m_owed += sim_seconds;
    if (m_owed + 1e-9 >= m_controls.dt) count = 1, m_owed -= m_controls.dt;
  } else {
    m_owed = 0;
  }
  long done = 0;
  m_stats.behind = false;
  for (; done < count && m_failure.empty(); ++done) {
    if (std::chrono::duration<double>(clock::now() - start).count() > wall_budget) {
      m_stats.behind = true;
      break;
    }
    step_once();
  }
  if (done > 0 && m_failure.empty()) check(true);
  const double wall = std::chrono::duration<double>(clock::now() - start).count();
  if (count > 0) // a frame with no step due (a step longer than a frame) keeps the last factor
    m_stats.realtime_factor = wall > 0 ? static_cast<double>(done) * m_controls.dt / wall : 0.0;
  refresh_stats();
}

template <int dim> long LiveSim<dim>::steps(long n) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  long done = 0;
  for (; done < n && m_failure.empty(); ++done) step_once();
  const double wall = std::chrono::duration<double>(clock::now() - start).count();
  m_stats.realtime_factor = wall > 0 ? static_cast<double>(done) * m_controls.dt / wall : 0.0;
  return done;
}

template <int dim> void LiveSim<dim>::refresh_stats() {
  const int n = std::min(m_step_count, static_cast<int>(m_step_us.size()));
  if (n > 0) {
    std::array<double, 256> tmp = m_step_us;
    std::nth_element(tmp.begin(), tmp.begin() + n / 2, tmp.begin() + n);
    m_stats.step_median_us = tmp[static_cast<std::size_t>(n / 2)];
  }
  if (m_failure.empty()) {
    m_stats.energy = elastic_energy(m_model->net, m_state.u) + kinetic_energy(m_model->net, m_state.v);
    m_stats.max_strain = max_strain(m_model->net, m_state.u);
    if (const auto* f = dynamic_cast<const FilteredImplicit<dim>*>(m_integ.get()))
      m_stats.fallback_steps = f->fallback_steps();
  }
}

template <int dim> void LiveSim<dim>::single_step() {
  if (m_failure.empty()) step_once();
}

template <int dim> int LiveSim<dim>::add_pull(int node, const Vec<dim>& target, bool pinned) {
  if (m_num_pulls >= kMaxPulls || node < 0 || node >= m_model->num_nodes()) return -1;
  Pull<dim>& p = m_pulls[static_cast<std::size_t>(m_num_pulls)];
  p = Pull<dim>{};
  p.node = node;
  p.target = target;
  p.pinned = pinned;
  p.nodes[0] = node;
  p.count = 1;
  // The patch: the boundary nodes within the grab radius of a boundary node at rest, the
  // nearest Pull::kMaxNodes of them (as many as the implicit filters couple node by node).
  const auto& rest = m_model->net.rest;
  if (m_grab_radius > 0 && m_on_boundary[static_cast<std::size_t>(node)]) {
    std::array<std::pair<double, int>, Pull<dim>::kMaxNodes> near{};
    for (int i = 0; i < m_model->num_nodes(); ++i) {
      const double d2 = (rest.col(i) - rest.col(node)).squaredNorm();
      if (i == node || !m_on_boundary[static_cast<std::size_t>(i)] || d2 > m_grab_radius * m_grab_radius) continue;
      // Kept sorted: the farthest kept drops out when a nearer one comes.
      int at = p.count - 1;
      if (p.count == Pull<dim>::kMaxNodes) {
        if (d2 >= near[static_cast<std::size_t>(at)].first) continue;
        --at;
      } else {
        ++p.count;
      }
      while (at >= 1 && near[static_cast<std::size_t>(at)].first > d2) {
        near[static_cast<std::size_t>(at) + 1] = near[static_cast<std::size_t>(at)];
        --at;
      }
      near[static_cast<std::size_t>(at) + 1] = {d2, i};
    }
    for (std::size_t q = 1; q < static_cast<std::size_t>(p.count); ++q) p.nodes[q] = near[q].second;
  }
  for (std::size_t q = 0; q < static_cast<std::size_t>(p.count); ++q) p.weights[q] = 1.0 / p.count;
  return m_num_pulls++;
}

template <int dim> void LiveSim<dim>::move_pull(int index, const Vec<dim>& target) {
  if (index >= 0 && index < m_num_pulls) m_pulls[static_cast<std::size_t>(index)].target = target;
}

template <int dim> void LiveSim<dim>::remove_pull(int index) {
  if (index < 0 || index >= m_num_pulls) return;
  for (int k = index; k + 1 < m_num_pulls; ++k)
    m_pulls[static_cast<std::size_t>(k)] = m_pulls[static_cast<std::size_t>(k) + 1];
  --m_num_pulls;
}

template <int dim> void LiveSim<dim>::clear_unpinned() {
  for (int k = m_num_pulls - 1; k >= 0; --k)
    if (!m_pulls[static_cast<std::size_t>(k)].pinned) remove_pull(k);
}

template <int dim> int LiveSim<dim>::probe_trace(float* out) const {
  return m_trace.copy_to(out);
}

template class LiveSim<2>;
template class LiveSim<3>;

} // namespace vtb
