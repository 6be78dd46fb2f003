#pragma once
/// \file
/// Scene files (TOML, SI units): what is simulated, on which mesh, with which solver.
/// The key names are the contract of docs/scenes.md. Parsing validates every value; vectors
/// whose length depends on the mesh dimension are checked when the mesh is known
/// (see model_builder.hh).

#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/problem/solver_names.hh"
#include "vtb/problem/solver_settings.hh"

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vtb {

/// A region as written in a scene: exactly one of box, group, point.
struct RegionDesc {
  std::optional<std::pair<Eigen::VectorXd, Eigen::VectorXd>> box; ///< [min, max]
  std::string group;
  std::optional<Eigen::VectorXd> point;
  std::optional<std::pair<Eigen::VectorXd, double>> disc; ///< loads only: {center, radius}
  std::string label;                                      ///< "fix[0]", "load[1]", ... or the entry's `name`
};

struct FixDesc {
  RegionDesc region;
};

/// Force control: total_force spread over the region, switched on at `start` over `ramp`.
struct LoadDesc {
  RegionDesc region;
  Eigen::VectorXd total_force;
  double start = 0.0;
  double ramp = 0.0;
};

/// Displacement control of a region; its reaction force is reported.
struct DriveDesc {
  RegionDesc region;
  Eigen::VectorXd displacement;
  double start = 0.0;
  double ramp = 0.0;
};

/// A probe records the displacement of the node nearest `point`, or with `load` set the
/// displacement under that load: its nodes' mean, each weighted by its share of the load's
/// force (for a uniform traction, by area), which is the displacement the load works through.
struct ProbeDesc {
  std::string name;
  Eigen::VectorXd point; ///< empty with `load`
  std::string load;      ///< a [[load]]'s name, or empty
};

struct MaterialDesc {
  double young_modulus = 0;    ///< Pa
  double poisson_ratio = 0;    ///< the FEM uses it; springs report their own effective value
  double density = 0;          ///< kg/m^3
  double thickness = 1.0;      ///< m, 2D plane stress only
  double retardation_time = 0; ///< s, Kelvin-Voigt tau = eta / E
  double mass_damping = 0;     ///< 1/s
};

struct MeshDesc {
  std::filesystem::path file; ///< resolved against the scene's folder: a .msh, or the surface (shape "surface")
  std::string shape;          ///< "rectangle" | "box" | "surface" when generated
  Eigen::VectorXd size;
  Eigen::VectorXi divisions;         ///< structured
  std::string mesher = "structured"; ///< "structured" | "cgal" (unstructured, about `nodes` nodes)
  int nodes = 0;                     ///< cgal; 0 for a surface meshed at `cell_size`
  double hole = 0;                   ///< m, radius of a central hole (cgal rectangle); 0: none
  double cell_size = 0;              ///< m, a surface's element size (when no nodes)
  double scale = 1;                  ///< multiplies a surface's coordinates
  std::vector<Refinement> refine;    ///< grading toward points (cgal box, surface)
  bool generated() const { return !shape.empty(); }
};

/// A scene's [solver], parsed once into its typed parts; every default is here.
struct SolverDesc {
  std::string kind = solvers::kFiltered; ///< explicit | filtered | implicit-euler | cvode | fem
  double dt = 1e-3;
  /// The scene named `dt`: a haptics session then steps its physics at it; without it the
  /// session picks its physics' step from the body's measured cost (docs/haptics.md).
  bool dt_given = false;
  std::string springs = "auto"; ///< auto (fitted within its budget, else lloyd) | lloyd | van-gelder | fitted
  SpringStepSettings step;
  CvodeSettings cvode;
  FemSettings fem;
};

struct HandDesc {
  /// [x, y] in the device's plane, or [x, y, z] points of a 3D scene (projected onto the plane).
  std::vector<Eigen::VectorXd> waypoints;
  double duration = 0;
  double grip_stiffness = 0;
};

/// Where the 2-DOF device's plane lies in a 3D body: world = origin + hx x_axis + hy y_axis.
struct DevicePlaneDesc {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX(), y_axis = Eigen::Vector3d::UnitY(); ///< unit, orthogonal
};

struct HapticsDesc {
  /// procat-sim | replay | null | plugin (a driver's shared library, device_abi.h) | udp (a device
  /// in another process, docs/devices.md "The UDP bridge")
  std::string device = "procat-sim";
  std::filesystem::path plugin;            ///< device = "plugin": the library, resolved against the scene's folder
  std::string plugin_config;               ///< handed to the plug-in's open as it is
  std::string address = "127.0.0.1:47000"; ///< device = "udp": HOST:PORT vtb binds
  double link_watchdog = 0.05;             ///< s: a udp link silent this long gets 0 N
  double rate = 1000.0;
  double coupling_stiffness = 400.0;
  double coupling_damping = 2.0;
  double max_force = 4.0;
  /// m: the tool tip's radius (a flat pad; 0: a point proxy); unset: tip_radius() decides.
  std::optional<double> tip_radius;
  /// The tip's radius for a body of `dim`: the scene's, else 4 mm in 3D (a physical tool) and a
  /// point proxy in 2D (docs/haptics.md: a pad on the 2D membranes does not hold steady yet).
  double tip_radius_for(int dim) const { return tip_radius ? *tip_radius : (dim == 3 ? 0.004 : 0.0); }
  std::optional<HandDesc> hand;
  /// [[haptics.probe]]: further devices, each held by a scripted hand of its own (probe 1, 2, ...;
  /// [haptics.hand] is probe 0). Their contact forces act on the body in the same step.
  std::vector<HandDesc> probes;
  /// [haptics.plane], 3D scenes only; absent = the x-y plane through the middle of the body in z.
  std::optional<DevicePlaneDesc> plane;
};

struct Scene {
  std::filesystem::path file; ///< the scene file itself (for messages)
  std::string name;
  double duration = 0;
  double output_interval = 0;
  MeshDesc mesh;
  MaterialDesc material;
  std::vector<FixDesc> fixes;
  std::vector<LoadDesc> loads;
  std::vector<DriveDesc> drives;
  Eigen::VectorXd initial_velocity;         ///< empty = zero
  Eigen::VectorXd initial_angular_velocity; ///< 1 value in 2D, 3 in 3D; empty = zero
  std::vector<ProbeDesc> probes;
  SolverDesc solver;
  std::optional<HapticsDesc> haptics;
};

/// Reads and validates a scene file. Throws InputError with "FILE:LINE: [table].key: problem"
/// for a syntax error, an unknown key (with the nearest known key suggested), a missing
/// required key, a wrong type or a value out of range.
Scene read_scene(const std::filesystem::path& file);

/// Same, from text (for tests and fuzzing); `name` stands for the file in messages and
/// relative paths resolve against `base_dir`.
Scene parse_scene(std::string_view text, const std::string& name, const std::filesystem::path& base_dir);

/// Levenshtein distance, for "did you mean" suggestions.
std::size_t edit_distance(std::string_view a, std::string_view b);

} // namespace vtb
