// The deep press (deep_press.csv): a soft layer pressed by a uniform pressure on a disc to a
// third of its thickness, statically, by the springs and by three continua (docs/fem.md).
#include "reproduce_parts.hh"
#include "vtb/problem/solver_names.hh"

#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/meshes/msh_io.hh"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <tuple>

namespace vtb::harness::parts {
namespace {

std::string block_scene(const std::filesystem::path& mesh, double nu) {
  std::ostringstream os;
  os << std::setprecision(17) << R"([scene]
name = "deep-press"
duration = 1.0
output_interval = 0.1
[mesh]
file = ")" << mesh.string()
     << R"("
[material]
young_modulus = )"
     << kDeepPressE << R"(
poisson_ratio = )"
     << nu << R"(
density = 1000.0
retardation_time = 0.05
[[fix]]
group = "front"
[[load]]
disc = { center = [0.02, 0.02, )"
     << kDeepPressH << "], radius = " << kDeepPressRadius << R"( }
total_force = [0.0, 0.0, -1.0]
ramp = 0.3
[[probe]]
name = "centre"
point = [0.02, 0.02, )"
     << kDeepPressH << R"(]
[solver]
kind = "implicit-euler"
dt = 0.02
)";
  return os.str();
}

/// The problem with its loads scaled by s.
template <class P> P scaled(const P& p, double s) {
  P q = p;
  for (auto& l : q.loads) {
    l.force *= s;
    l.total *= s;
  }
  return q;
}

} // namespace

void write_deep_press(const std::filesystem::path& out, bool quick, std::ostream* log) {
  const int nodes = quick ? 700 : 1500;
  if (log) *log << "[deep press] a " << kDeepPressH * 1e3 << " mm layer, ~" << nodes << " nodes, pressed to 40 %\n";
  // One CGAL mesh for every model and material: a 40 x 40 mm layer on a clamped base.
  const std::filesystem::path mesh = out / "deep_press_block.msh";
  {
    const Scene g = parse_scene(R"([scene]
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [0.04, 0.04, )" + std::to_string(kDeepPressH) +
                                    "], mesher = \"cgal\", nodes = " + std::to_string(nodes) + R"( }
[material]
young_modulus = 1.0
poisson_ratio = 0.3
density = 1.0
)",
                                "deep_press.toml", out);
    std::filesystem::create_directories(out);
    write_msh(std::get<Mesh3>(load_mesh(g)), mesh);
  }
  // Load levels: multiples of F30, the force that presses the linear continuum 30 % deep, from
  // 0 to 2 F30 in equal steps; each continuum follows them as one static path (the load ramps
  // over the run's second, an equilibrium at every sample), the springs run to rest at each.
  const int steps = quick ? 8 : 16;
  std::ostringstream os;
  os << std::setprecision(6) << "poisson_ratio,model,nodes,level,force,depth,depth_ratio,converged\n";
  auto mark = std::chrono::steady_clock::now();
  const auto seconds = [&mark] { // since the last call
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return std::round(10 * s) / 10;
  };
  for (const double nu : {0.3, 0.45}) {
    const Scene scene = parse_scene(block_scene(mesh, nu), "deep_press.toml", out);
    const Model<3> model = build_model<3>(scene, std::get<Mesh3>(load_mesh(scene)), {}, false);
    const auto depth = [](const Trajectory<3>& tr, std::size_t k) { return -tr.probe_u.at(k).at(0).z(); };
    const auto row = [&](const std::string& name, double level, double force, double d, bool converged) {
      os << nu << ',' << name << ',' << model.num_nodes() << ',' << level << ',' << force << ',' << d << ','
         << d / kDeepPressH << ',' << (converged ? "true" : "false") << '\n';
    };
    // The linear continuum's compliance (P2, one static solve at the unit load).
    fem::FemOptions o;
    o.static_solve = true;
    o.degree = 2;
    Trajectory<3> unit;
    fem::simulate<3>(model, scene.material, o, unit);
    const double compliance = depth(unit, unit.t.size() - 1), f30 = 0.3 * kDeepPressH / compliance;
    // The continua along the path: the load ramps from 0 at t = 0 to 2 F30 at t = 1.
    Problem<3> path = scaled(static_cast<const Problem<3>&>(model), 2 * f30);
    path.duration = 1.0;
    path.output_interval = 1.0 / steps;
    for (auto& l : path.loads) l.ramp = 1.0;
    for (int k = 1; k <= steps; ++k) {
      const double level = 2.0 * k / steps;
      row("linear-p2", level, level * f30, level * f30 * compliance, true);
    }
    for (const auto& [name, law, degree] : {std::tuple{"neo-hookean-p2", fem::Kinematics::neo_hookean, 2},
                                            std::tuple{"neo-hookean-p1", fem::Kinematics::neo_hookean, 1},
                                            std::tuple{"svk-p1", fem::Kinematics::svk, 1}}) {
      o.degree = degree;
      o.kinematics = law;
      o.static_path = true;
      Trajectory<3> tr;
      fem::simulate<3>(path, scene.material, o, tr); // a collapse stops the path: its levels are missing
      for (std::size_t k = 1; k < tr.t.size(); ++k) {
        const double level = 2.0 * tr.t[k];
        const double d = depth(tr, k);
        row(name, level, level * f30, d, std::isfinite(d));
      }
      if (log)
        *log << "  nu " << nu << ": " << name << " to " << 2.0 * tr.t.back() << " F30 in " << seconds() << " s\n"
             << std::flush;
    }
    // The springs at rest under each level (at twice the continua's, for they soften early):
    // implicit Euler through the scene's 0.3 s ramp to 2 s; at rest when the last two samples
    // (0.1 s apart) agree to 1e-3.
    for (int k = 1; k <= 2 * steps; ++k) {
      const double level = 1.0 * k / steps;
      Model<3> loaded = scaled(model, level * f30);
      loaded.duration = 2.0;
      Trajectory<3> tr;
      const RunReport r = run_solver<3>(scene, loaded, solvers::kImplicitEuler, 0, tr);
      const std::size_t last = tr.t.size() - 1;
      const double d = r.stable ? depth(tr, last) : std::nan("");
      row("springs", level, level * f30, d, r.stable && std::abs(d - depth(tr, last - 1)) <= 1e-3 * std::abs(d));
    }
    if (log) *log << "  nu " << nu << ": springs in " << seconds() << " s\n" << std::flush;
  }
  std::filesystem::remove(mesh);
  write_files_atomically(out, {{"deep_press.csv", os.str()}});
}

} // namespace vtb::harness::parts
