#pragma once
/// \file
/// The reproduction's parts beyond the paper's own table (internal to the harness): each
/// writes one CSV into the output folder, which the paper (scripts/build_paper.sh) plots.

#include "vtb/springs/model.hh"

#include <filesystem>
#include <iosfwd>

namespace vtb::reproduction::parts {

/// The linear static displacement of the spring network under the loads at time t:
/// K_ff u_f = f_f, K the stiffness at rest over the free nodes (the small-load limit).
template <int dim> Nodal<dim> linear_static(const Model<dim>& model, double t);

/// meta.csv: key,value rows: quick, duration_s, cores, cpu (what the title page states).
/// meta.csv: quick or not, the simulated duration, the machine, and where the reproduction ran
/// (ranks.hh binding(): "serial, cpus ..." or rank 0's under mpirun).
void write_meta(const std::filesystem::path& out, bool quick, double duration, const std::string& binding);

/// creep.csv: the creep strip's tip displacement over time for filtered-full, implicit Euler
/// and CVODE beside the Kelvin-Voigt law u_static (1 - exp(-t / tau)), u_static from the
/// spring network's linear static solve.
void write_creep(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log);

/// transient.csv: the cantilever_step scene (a strip under a step load across its axis) at
/// dt = 1, 10 and 40 ms for filtered-full, filtered-tensor and implicit-euler: the tip
/// history's largest error relative to its peak, against CVODE at the scene's rtol (1e-10),
/// and the median step (the filters' lag, docs/fidelity.md).
void write_transient(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log);

/// haptics_periods.csv (each servo cycle's period) and haptics_trace.csv (t, handle and
/// force of the first probe) of a real-time session of haptic_press.toml with the physics
/// stalled at `stall_time`; haptics_summary.csv: misses, p99, fault and force-zero times.
/// tip_force.csv: the slab press (haptic_slab_press, lockstep) held at several depths on the
/// repository's two slab meshes, with the scene's 4 mm tool tip and with a point proxy, and the
/// half-space's force at each depth (docs/haptics.md).
void write_tip_force(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, bool quick,
                     std::ostream* log);
void write_haptics(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, double stall_time,
                   std::ostream* log);

/// multirate_trace.csv and multirate_summary.csv: the slab press (`haptic_slab_press`) on a CGAL
/// slab of about kMultirateNodes nodes (Lloyd's springs, the tensor filter's block V-cycle): the
/// force sent to the device per servo cycle in lockstep at 1 kHz and in real time at the rate
/// the body affords (docs/haptics.md), the physics' step and time ratio, the held forces, the
/// servo cycle's cost. Runs the real-time session: call it with nothing else on the machine.
inline constexpr int kMultirateNodes = 10000;
void write_multirate(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log);

/// deep_press.csv: a soft layer (E kDeepPressE, kDeepPressH thick, 40 x 40 mm, a CGAL mesh of
/// ~700 nodes quick, ~1,500 full) clamped underneath, a uniform pressure on a disc of radius
/// kDeepPressRadius at the centre of its top, for nu 0.3 and 0.45: the static depth of the disc's
/// centre at loads up to twice the one that presses the linear continuum 30 % deep, for the
/// default springs (implicit Euler to rest), linear P2, St. Venant-Kirchhoff P1 and neo-Hookean
/// P1 and P2 (docs/fem.md, "Deep presses").
inline constexpr double kDeepPressE = 5e3, kDeepPressH = 0.01, kDeepPressRadius = 0.004;
void write_deep_press(const std::filesystem::path& out, bool quick, std::ostream* log);

/// scaling.csv: per mesh of a 2D rectangle, a 3D box and a CGAL slab ladder (about 2k and 10k
/// nodes, and 50k unless quick) and per solver (filtered-full, filtered-multigrid,
/// implicit-euler): nodes, springs, precompute, median step, the integrator's heap and the
/// largest displacement error against the FEM on the same mesh.
void write_scaling(const std::filesystem::path& out, bool quick, std::ostream* log);

/// fidelity.csv: per case (a strip in tension and in bending on a union-jack mesh, the paper's
/// plate under one and four forces, a 3D CGAL slab cantilever, Cook's membrane on a mapped
/// structured grid) and per calibration (lloyd, van-gelder, fitted): the linear static spring
/// solution against P1 FEM on the same mesh, relative L2 error over all nodes and at the node of
/// largest displacement, ||u_fem|| / ||u_springs|| (above 1: the springs are too stiff) and the
/// calibration's wall time (a cache read when calibration_cached is true: fitted_cache.hh). Both linear: the difference
/// is the springs alone. The slab's mesh is the scenes' canonical one (scenes_dir/../../meshes/data).
void write_fidelity(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log);

} // namespace vtb::reproduction::parts
