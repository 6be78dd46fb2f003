#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/problem/output.hh"

namespace vtb::fem {

RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames) {
  FemOptions o = options_from(scene.solver);
  if (frames) o.frames_dir = out_dir / "frames";
  return with_problem(scene, [&](const auto& model) {
    constexpr int dim = std::decay_t<decltype(model)>::dimension;
    Trajectory<dim> traj;
    if (mpi_size() > 1) {
      if (frames) throw InputError("--frames is not available under MPI yet");
      const RunReport rep = simulate_distributed<dim>(model, scene.material, o, traj);
      if (mpi_rank() == 0) write_run_outputs(out_dir, model, traj, rep, scene.name);
      return rep;
    }
    const RunReport rep = simulate<dim>(model, scene.material, o, traj);
    write_run_outputs(out_dir, model, traj, rep, scene.name);
    if (frames) write_pvd(out_dir, traj.t);
    return rep;
  });
}

} // namespace vtb::fem
