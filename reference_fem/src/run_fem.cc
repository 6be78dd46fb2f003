#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/problem/output.hh"

namespace vtb::fem {

RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames, RunTables* tables) {
  FemOptions o = options_from(scene.solver);
  frames = frames && !out_dir.empty();
  if (frames) o.frames_dir = out_dir / "frames";
  return with_problem(scene, [&](const auto& model) {
    constexpr int dim = std::decay_t<decltype(model)>::dimension;
    Trajectory<dim> traj;
    if (mpi_size() > 1) {
      if (frames) throw InputError("--frames is not available under MPI yet");
      const RunReport rep = simulate_distributed<dim>(model, scene.material, o, traj);
      if (mpi_rank() == 0) finish_run(out_dir, model, traj, rep, scene.name, tables);
      return rep;
    }
    const RunReport rep = simulate<dim>(model, scene.material, o, traj);
    finish_run(out_dir, model, traj, rep, scene.name, tables);
    if (frames) write_pvd(out_dir, traj.t);
    return rep;
  });
}

} // namespace vtb::fem
