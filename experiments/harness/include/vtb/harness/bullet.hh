#pragma once
/// \file
/// The harness's `bullet` solver: Bullet's deformable mass-spring world (experiments/peers)
/// with its one stiffness fitted to the FEM's static answer (docs/peers.md).

#include "vtb/problem/output.hh"
#include "vtb/problem/run_report.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/model.hh"

#include <filesystem>

namespace vtb::harness {

/// The uniform link stiffness whose network stores, in the FEM's static state of the scene,
/// the strain energy the FEM stores there: k = E_fem / E_1 with E_fem = W / 2 (Clapeyron: half
/// the work of the loads and the driven supports' reactions on the FEM's static displacement)
/// and E_1 = sum over springs of (n . (u_j - u_i))^2 / 2, the linear network's energy at unit
/// stiffness in the same displacement. InputError if the scene loads nothing.
template <int dim> double bullet_stiffness(const Scene& scene, const Model<dim>& model);

/// Runs the scene with Bullet at step dt: the network with k = bullet_stiffness and dashpots
/// c = tau k (the scene's retardation time), sampled like every spring solver.
template <int dim> RunReport run_bullet(const Scene& scene, const Model<dim>& model, double dt, Trajectory<dim>& out);

/// What `vtb run --solver bullet` does: run_bullet on the scene's model at its dt, and the
/// outputs of every `vtb run` (probes.csv, reactions.csv, summary.json, frames if asked).
RunReport run_bullet_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames,
                           RunTables* tables = nullptr);

} // namespace vtb::harness
