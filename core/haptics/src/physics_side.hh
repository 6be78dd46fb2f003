#pragma once
/// \file
/// The physics side of a haptics session: one spring-solver step with the probes' contact
/// forces applied (each the spring to the anchor the servo's cycles held since the last publish:
/// applied_force), then the deformed body and each probe's local contact model published for
/// the servo.

#include "exchange.hh"
#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/coupling.hh"
#include "vtb/haptics/session.hh"
#include "vtb/haptics/triple_buffer.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/springs/spring_kernels.hh"

#include <chrono>
#include <limits>
#include <memory>
#include <vector>

namespace vtb {

template <int dim> class Physics {
public:
  using Mat = Eigen::Matrix<double, dim, dim>;

  /// `period`: the servo's; a physics stepping slower hands the servo local models (a physics
  /// stepping every period needs none: the servo sees each step). `fallback`: the compliance
  /// (m/N) a local model takes where the solver has none of its own (half_space_tip_compliance).
  Physics(const Model<dim>& model, const IntegratorOptions& o, TripleBuffer<Snapshot<dim>>& snap,
          TripleBuffer<Commands<dim>>& cmd, const HapticsDesc& h, const HapticsOptions& faults, double period,
          double fallback)
      : m_model(model), m_integ(make_integrator(model, o)), m_state(initial_state(model)), m_snap(snap), m_cmd(cmd),
        m_k(h.coupling_stiffness), m_b(h.coupling_damping), m_faults(faults), m_slow(o.dt > period * (1 + 1e-9)),
        m_multirate(m_slow && faults.local_model && h.tip_radius_for(dim) > 0), m_fallback(fallback) {
    m_state.applied = Nodal<dim>::Zero(dim, model.num_nodes());
    m_state.applied_stiffness = Eigen::VectorXd::Zero(model.num_nodes());
    m_state.applied_damping = Eigen::VectorXd::Zero(model.num_nodes());
    m_state.applied_group = Eigen::VectorXi::Constant(model.num_nodes(), -1);
  }

  /// Before each publish, builds the next contact tree of `contacts` on this thread (Contacts::prepare).
  void build_contact_trees_for(Contacts<dim>& contacts) { m_trees = &contacts; }

  double dt() const { return m_integ->dt(); }
  double time() const { return m_state.t; }
  /// Where the compliance of the local models came from: the solver's own system, the
  /// half-space's under the tip, or none (a physics stepping every servo period).
  const char* compliance_source() const {
    return !m_multirate ? "none" : m_solver_compliance ? "solver" : m_fallback > 0 ? "half-space" : "none";
  }

  /// Steps once; false when a stall fault has stopped the physics.
  bool step() {
    using F = HapticsOptions::Fault;
    if (m_faults.fault == F::stall && m_state.t >= m_faults.fault_time) return false;
    m_cmd.fetch();
    m_state.applied.setZero();
    m_state.applied_stiffness.setZero();
    m_state.applied_damping.setZero();
    m_state.applied_group.setConstant(-1);
    // Each probe's force on its footprint's nodes by their weights, and the coupling's
    // stiffness and damping with it, one group per probe, for the integrators that solve them
    // implicitly: the proxy is sum_k w_k x_k along the tip's normal, so the coupling's k acts as
    // k w w^T (coupling_set.hh). Explicitly, a 400 N/m coupling on a node of 0.04 g is beyond
    // the step's limit at dt = 1 ms (sqrt(m/k) = 0.33 ms). A physics stepping every servo
    // period takes the last cycle's force; a slower one the spring to the anchor the servo's
    // cycles held since it saw the last publish (applied_force).
    Snapshot<dim>& s = m_snap.back();
    int group = 0;
    for (const ContactCommand<dim>& c : m_cmd.front()) {
      if (m_slow && c.footprint.count == 0 && c.history.touched.count > 0) { // a contact that ended
        apply_force_to_body<dim>(c.history.touched, ended_contact_force<dim>(c.history), m_state);
        s.models[static_cast<std::size_t>(group++)].valid = false;
        continue;
      }
      const Vec<dim> f = m_slow && c.history.cycles > 0 ? applied_force<dim>(c.history, footprint_position(c.footprint),
                                                                             tip_stiffness(m_k, c.footprint))
                                                        : Vec<dim>(c.force_on_body);
      if (c.footprint.count > 0) apply_to_body<dim>(c.footprint, f, m_k, m_b, group, m_state);
      LocalModel<dim>& model = s.models[static_cast<std::size_t>(group)];
      model.valid = m_multirate && c.footprint.count > 0;
      model.applied = f;
      ++group;
    }
    const auto a = std::chrono::steady_clock::now();
    m_integ->step(m_state);
    m_step_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count());
    for (int g = 0; g < group; ++g) {
      LocalModel<dim>& model = s.models[static_cast<std::size_t>(g)];
      if (!model.valid) continue;
      Mat c;
      if (m_integ->coupling_compliance(g, c) && c.allFinite()) {
        model.compliance = c;
        m_solver_compliance = true;
      } else {
        model.compliance = m_fallback * Mat::Identity();
        model.valid = m_fallback > 0;
      }
    }
    s.t = m_state.t;
    s.x = m_model.net.rest + m_state.u;
    s.v = m_state.v;
    if (m_faults.fault == F::nan && m_state.t >= m_faults.fault_time)
      s.x.setConstant(std::numeric_limits<double>::quiet_NaN());
    s.finite = s.x.allFinite() && s.v.allFinite() && max_strain(m_model.net, m_state.u) < 10.0;
    // The next contact tree is built on this shape before it is published, so that the servo,
    // refitting to it, finds that tree offered and adopts it: a build (milliseconds on a 20k-node
    // body) is never the servo's, whatever the physics' step moved (Contacts::prepare).
    if (m_trees != nullptr && s.finite) m_trees->prepare(s.x);
    m_snap.publish();
    return true;
  }

  const std::vector<double>& step_times() const { return m_step_us; }

private:
  /// w . x of a footprint on the body now.
  Vec<dim> footprint_position(const Footprint& fp) const {
    return footprint_mean<dim>(fp, m_model.net.rest) + footprint_mean<dim>(fp, m_state.u);
  }

  const Model<dim>& m_model;
  std::unique_ptr<Integrator<dim>> m_integ;
  State<dim> m_state;
  TripleBuffer<Snapshot<dim>>& m_snap;
  TripleBuffer<Commands<dim>>& m_cmd;
  double m_k, m_b; ///< the virtual coupling's stiffness and damping
  HapticsOptions m_faults;
  bool m_slow; ///< steps slower than the servo
  /// And local models asked for, with a tool tip: the servo gets them. A point proxy's compliance
  /// is the mesh's (the continuum's is singular under a point load), and on the 2D press's
  /// membrane it made the servo's prediction 20x worse than the free motion at a 40 ms step.
  bool m_multirate;
  double m_fallback; ///< m/N: the half-space's compliance under the tip (0: none)
  bool m_solver_compliance = false;
  Contacts<dim>* m_trees = nullptr; ///< whose contact trees this thread builds (real time)
  std::vector<double> m_step_us;
};

} // namespace vtb
