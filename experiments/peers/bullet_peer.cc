#include "bullet_peer.hh"
#include "vtb/problem/solver_names.hh"

#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableLagrangianForce.h>
#include <BulletSoftBody/btDeformableMassSpringForce.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <btBulletDynamicsCommon.h>

#include <string_view>
#include <vector>

namespace vtb::peers {

template <int dim> Model<dim> uniform_network(const Model<dim>& model, double k, double c) {
  Model<dim> m = model;
  m.net.stiffness.setConstant(k);
  m.net.damping.setConstant(c);
  m.net.calibration = "bullet-uniform";
  return m;
}

namespace {

using TVStack = btAlignedObjectArray<btVector3>;

/// The scene's loads at the step's end as a Lagrangian force: Bullet's deformable solver
/// reads forces only from these (a node's m_f is not used). Position independent, so it has
/// no differentials.
class LoadForce final : public btDeformableLagrangianForce {
public:
  const std::vector<btVector3>* load = nullptr; ///< per node
  void addScaledForces(btScalar scale, TVStack& force) override { add(scale, force); }
  void addScaledExplicitForce(btScalar scale, TVStack& force) override { add(scale, force); }
  void addScaledDampingForce(btScalar, TVStack&) override {}
  void addScaledDampingForceDifferential(btScalar, const TVStack&, TVStack&) override {}
  void buildDampingForceDifferentialDiagonal(btScalar, TVStack&) override {}
  void addScaledElasticForceDifferential(btScalar, const TVStack&, TVStack&) override {}
  btDeformableLagrangianForceType getForceType() override { return BT_GRAVITY_FORCE; }

private:
  void add(btScalar scale, TVStack& force) const {
    for (int b = 0; b < m_softBodies.size(); ++b)
      for (int i = 0; i < m_softBodies[b]->m_nodes.size(); ++i)
        force[m_softBodies[b]->m_nodes[i].index] += scale * (*load)[static_cast<std::size_t>(i)];
  }
};

template <int dim> btVector3 to_bt(const Vec<dim>& v) {
  return btVector3(v(0), v(1), dim == 3 ? v(dim - 1) : 0.0);
}

template <int dim> class BulletIntegrator final : public Integrator<dim> {
public:
  BulletIntegrator(const Model<dim>& model, const BulletOptions& o)
      : Integrator<dim>(o.dt), m_model(model), m_dispatcher(&m_config),
        m_world(&m_dispatcher, &m_broadphase, &m_constraints, &m_config, &m_solver),
        m_springs(o.stiffness, o.damping, true) {
    m_constraints.setDeformableSolver(&m_solver);
    m_world.setGravity(btVector3(0, 0, 0));
    m_world.getWorldInfo().m_gravity.setValue(0, 0, 0);
    m_world.getWorldInfo().m_maxDisplacement = 1e30; // no clamp of the nodes' velocities
    // Bullet's default scheme: elastic forces explicit, dashpots implicit (CG). Its implicit
    // mode (setImplicit(true), Newton on backward Euler) left every node at rest in Debian's
    // 3.24, even a free body under Bullet's own gravity force (docs/peers.md).
    m_world.setImplicit(false);
    const int n = model.num_nodes();
    std::vector<btVector3> x(static_cast<std::size_t>(n));
    std::vector<btScalar> mass(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      x[static_cast<std::size_t>(i)] = to_bt<dim>(model.net.rest.col(i));
      mass[static_cast<std::size_t>(i)] = model.constrained[static_cast<std::size_t>(i)] ? 0.0 : model.net.mass[i];
    }
    m_body = std::make_unique<btSoftBody>(&m_world.getWorldInfo(), n, x.data(), mass.data());
    for (const auto& e : model.net.edge) m_body->appendLink(e[0], e[1]);
    // Rest lengths from the rest positions now: Bullet would take them from wherever the
    // nodes are at its first step.
    m_body->updateConstants();
    m_body->m_bUpdateRtCst = false;
    m_body->m_cfg.collisions = 0;
    m_body->setSelfCollision(false);
    m_body->setActivationState(DISABLE_DEACTIVATION);
    m_world.addSoftBody(m_body.get());
    m_world.addForce(m_body.get(), &m_springs);
    m_load.resize(static_cast<std::size_t>(n));
    m_loads.load = &m_load;
    m_world.addForce(m_body.get(), &m_loads);
    m_force = Nodal<dim>::Zero(dim, n);
    m_next = initial_state(model);
  }
  ~BulletIntegrator() override { m_world.removeSoftBody(m_body.get()); }

  void step(State<dim>& s) override {
    const double dt = this->dt();
    m_model.external_forces(s.t + dt, m_force);
    if (s.applied.cols() == m_force.cols()) m_force += s.applied;
    for (int i = 0; i < m_model.num_nodes(); ++i) m_load[static_cast<std::size_t>(i)] = to_bt<dim>(m_force.col(i));
    // Supports and drives: massless nodes moved to where the scene puts them at t + dt (only
    // the constrained columns of m_next are written and read).
    m_model.apply_constraints(s.t + dt, m_next.u, m_next.v);
    // The state is the caller's: Bullet's nodes start every step from it.
    for (int i = 0; i < m_model.num_nodes(); ++i) {
      btSoftBody::Node& node = m_body->m_nodes[i];
      node.m_x = node.m_q = to_bt<dim>(Vec<dim>(m_model.net.rest.col(i) + s.u.col(i)));
      const bool moved = m_model.constrained[static_cast<std::size_t>(i)];
      node.m_v = node.m_vn = to_bt<dim>(moved ? Vec<dim>((m_next.u.col(i) - s.u.col(i)) / dt) : Vec<dim>(s.v.col(i)));
    }
    m_world.stepSimulation(dt, 0);
    for (int i = 0; i < m_model.num_nodes(); ++i) {
      const btSoftBody::Node& node = m_body->m_nodes[i];
      for (int c = 0; c < dim; ++c) {
        s.u(c, i) = node.m_x[c] - m_model.net.rest(c, i);
        s.v(c, i) = node.m_v[c];
      }
    }
    s.t += dt;
    m_model.apply_constraints(s.t, s.u, s.v);
  }
  std::string_view name() const override { return solvers::kBullet; }

private:
  const Model<dim>& m_model;
  btSoftBodyRigidBodyCollisionConfiguration m_config;
  btCollisionDispatcher m_dispatcher;
  btDbvtBroadphase m_broadphase;
  btDeformableBodySolver m_solver;
  btDeformableMultiBodyConstraintSolver m_constraints;
  btDeformableMultiBodyDynamicsWorld m_world;
  btDeformableMassSpringForce m_springs;
  LoadForce m_loads;
  std::unique_ptr<btSoftBody> m_body;
  std::vector<btVector3> m_load;
  Nodal<dim> m_force;
  State<dim> m_next;
};

} // namespace

template <int dim>
std::unique_ptr<Integrator<dim>> make_bullet_integrator(const Model<dim>& model, const BulletOptions& options) {
  return std::make_unique<BulletIntegrator<dim>>(model, options);
}

template Model<2> uniform_network<2>(const Model<2>&, double, double);
template Model<3> uniform_network<3>(const Model<3>&, double, double);
template std::unique_ptr<Integrator<2>> make_bullet_integrator<2>(const Model<2>&, const BulletOptions&);
template std::unique_ptr<Integrator<3>> make_bullet_integrator<3>(const Model<3>&, const BulletOptions&);

} // namespace vtb::peers
