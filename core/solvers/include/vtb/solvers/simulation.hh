#pragma once
/// \file
/// Running a scene with a spring solver: the time loop, sampling, stability watch, timing.

#include "vtb/problem/output.hh"
#include "vtb/problem/run_report.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/springs/model.hh"

#include <filesystem>
#include <functional>
#include <memory>
#include <span>

namespace vtb {

/// A run stops as unstable when the state is non-finite or a spring's strain exceeds this.
inline constexpr double kRunawayStrain = 10.0;

/// Runs `model` with the integrator options; samples at sample_times(duration, interval),
/// interpolated linearly within the step that contains each (the run takes ceil(D / dt) steps). Never throws for a
/// numerical blow-up: it stops the run and reports stable = false.
template <int dim>
RunReport simulate(const Model<dim>& model, const IntegratorOptions& options, Trajectory<dim>& out,
                   bool record_field = false);

/// Makes the integrator a run steps with (its time is the run's precompute).
template <int dim> using IntegratorFactory = std::function<std::unique_ptr<Integrator<dim>>()>;

/// simulate()'s time loop with an integrator that `make` builds: how a peer library's stepper
/// (the harness's Bullet solver) is run, sampled and watched like the spring integrators.
template <int dim>
RunReport simulate_with(const Model<dim>& model, const IntegratorOptions& options, const IntegratorFactory<dim>& make,
                        Trajectory<dim>& out, bool record_field = false);

/// Support reactions at a state: minus the internal and external forces at its nodes.
template <int dim>
void support_reactions(const Model<dim>& model, const State<dim>& s, Nodal<dim>& scratch, Nodal<dim>& ext,
                       std::vector<Vec<dim>>& out);

/// Appends the sample of state s to traj (time, probes, support reactions, the whole field and
/// velocity if record_field), and raises rep's max_strain and max_spring_strain to the sample's. Shared by every spring
/// solver.
template <int dim>
void record_sample(const Model<dim>& model, const State<dim>& s, Trajectory<dim>& traj, bool record_field,
                   RunReport& rep);

/// Writes frames/frame_NNNN.vtu (one per sample of a trajectory recorded with its field) and
/// frames.pvd into dir: displacement and velocity per node, the largest principal strain and
/// the mean spring force per cell (compressed binary VTU).
template <int dim>
void write_frames(const Model<dim>& model, const Trajectory<dim>& traj, const std::filesystem::path& dir);

/// The spring integrators' options from [solver].
IntegratorOptions integrator_options(const SolverDesc& solver);

namespace solvers {
struct Entry;
/// What a spring entry of the registry runs with: the scene's [solver] options, kind and
/// filter set by the entry.
IntegratorOptions integrator_options(const Entry& entry, const SolverDesc& solver);
} // namespace solvers

/// Everything `vtb run` does with a spring solver: load mesh, build model, simulate, write
/// probes.csv, reactions.csv and summary.json into `out_dir` (all or nothing), and with
/// `frames` frames.pvd + frames/frame_NNNN.vtu, one per sample; `progress` is told how a
/// spring fit advances. An empty `out_dir` writes nothing; `tables`, when set, receives what
/// the files hold (finish_run); `yardstick`: what the springs' load check measures against
/// (build_model). Returns the report.
RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames = false,
                    const FitProgress& progress = {}, RunTables* tables = nullptr,
                    const Yardstick* yardstick = nullptr);

} // namespace vtb
