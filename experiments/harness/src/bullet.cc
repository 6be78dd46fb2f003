#include "vtb/harness/bullet.hh"

#include "bullet_peer.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/problem/output.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/solvers/simulation.hh"

#include <chrono>

namespace vtb::harness {

template <int dim> double bullet_stiffness(const Scene& scene, const Model<dim>& model) {
  fem::FemOptions o = fem::options_from(scene.solver);
  o.static_solve = true;
  o.kinematics = fem::Kinematics::linear; // the linear springs are fitted to the linear continuum
  Trajectory<dim> fem;
  const RunReport r = fem::simulate<dim>(model, scene.material, o, fem, true);
  if (!r.stable || fem.field.empty()) throw std::runtime_error("bullet: the FEM's static solve failed: " + r.failure);
  const Nodal<dim>& u = fem.field.back();
  const double t = fem.t.back();
  Nodal<dim> f(dim, model.num_nodes());
  model.external_forces(t, f);
  double work = (f.array() * u.array()).sum();
  for (std::size_t s = 0; s < model.supports.size(); ++s) {
    const Support<dim>& sup = model.supports[s];
    if (sup.driven) work += fem.reaction.back()[s].dot(ramp_factor(t, sup.start, sup.ramp) * sup.displacement);
  }
  double unit = 0;
  const auto& net = model.net;
  for (int sp = 0; sp < net.num_springs(); ++sp) {
    const int i = net.edge[static_cast<std::size_t>(sp)][0], j = net.edge[static_cast<std::size_t>(sp)][1];
    const Vec<dim> n = (net.rest.col(j) - net.rest.col(i)).normalized();
    const double stretch = n.dot(u.col(j) - u.col(i));
    unit += 0.5 * stretch * stretch;
  }
  if (!(work > 0) || !(unit > 0))
    throw InputError("bullet: the scene loads nothing, so no stiffness can be fitted to the FEM's static answer");
  return 0.5 * work / unit;
}

template <int dim> RunReport run_bullet(const Scene& scene, const Model<dim>& model, double dt, Trajectory<dim>& out) {
  const auto fit_start = std::chrono::steady_clock::now();
  const double k = bullet_stiffness(scene, model);
  const double fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_start).count();
  peers::BulletOptions bo;
  bo.dt = dt;
  bo.stiffness = k;
  bo.damping = scene.material.retardation_time * k;
  const Model<dim> uniform = peers::uniform_network(model, bo.stiffness, bo.damping);
  IntegratorOptions io;
  io.kind = solvers::kBullet;
  io.dt = dt;
  RunReport rep = simulate_with<dim>(
      uniform, io, [&] { return peers::make_bullet_integrator(uniform, bo); }, out, true);
  rep.solver = solvers::kBullet;
  rep.calibration_seconds = fit_seconds; // the FEM's static solve and the energy ratio
  return rep;
}

RunReport run_bullet_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames, RunTables* tables) {
  return with_model(scene, [&](const auto& model) {
    constexpr int dim = std::decay_t<decltype(model)>::dimension;
    Trajectory<dim> traj;
    const RunReport rep = run_bullet(scene, model, scene.solver.dt, traj);
    finish_run(out_dir, model, traj, rep, scene.name, tables);
    if (frames && !out_dir.empty()) write_frames(model, traj, out_dir);
    return rep;
  });
}

template double bullet_stiffness<2>(const Scene&, const Model<2>&);
template double bullet_stiffness<3>(const Scene&, const Model<3>&);
template RunReport run_bullet<2>(const Scene&, const Model<2>&, double, Trajectory<2>&);
template RunReport run_bullet<3>(const Scene&, const Model<3>&, double, Trajectory<3>&);

} // namespace vtb::harness
