#pragma once
/// \file
/// Bullet 3.24 as a peer solver (`bullet` in the registry): what a user might pick instead of
/// vtb. The closest model Bullet offers is its deformable world's mass-spring force
/// (btDeformableMultiBodyDynamicsWorld, btDeformableMassSpringForce with momentum-conserving
/// dashpots): linear springs and dashpots along each link, stepped by Bullet's default scheme
/// (the elastic forces explicit, the dashpots implicit by conjugate gradients). It has one
/// stiffness k and one damping c for every link, so the network is vtb's mesh edges with
/// uniform springs; how k is chosen is the harness's (docs/peers.md). Loads enter as a
/// Lagrangian force of their own, supports and drives as massless nodes moved by the scene.
/// Only the harness links Bullet (double precision); vtb::core does not. Bullet's step
/// allocates (its arrays and trees); the no-allocation rule is vtb's own steppers'.

#include "vtb/solvers/integrator.hh"
#include "vtb/springs/model.hh"

#include <memory>

namespace vtb::peers {

struct BulletOptions {
  double dt = 1e-3;
  double stiffness = 1.0; ///< N/m, every link
  double damping = 0.0;   ///< N s/m, every link
};

/// `model` with every spring's stiffness and damping replaced by the uniform k and c: the
/// network Bullet simulates, for recording and reporting what it computes.
template <int dim> Model<dim> uniform_network(const Model<dim>& model, double k, double c);

/// A stepper over Bullet's world, built from `model` (2D bodies lie in z = 0 and stay there:
/// the springs and loads are in-plane). `model` must outlive it.
template <int dim>
std::unique_ptr<Integrator<dim>> make_bullet_integrator(const Model<dim>& model, const BulletOptions& options);

} // namespace vtb::peers
