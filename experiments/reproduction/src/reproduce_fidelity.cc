// fidelity.csv: the spring network's own (calibration) error against the continuum (P2 refined
// until converged, vtb/fem/continuum.hh) and against P1 FEM on the same mesh, in the linear
// regime: all static and linear, so the differences are the springs' and the mesh's alone.
// deep_press.csv: the same springs far outside that regime, a soft layer pressed by a disc to a
// third of its thickness, statically, against three continua (docs/fem.md, "Deep presses").
#include "reproduce_parts.hh"
#include "vtb/problem/solver_names.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/fem/continuum.hh"
#include "vtb/fem/kelvin_voigt.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/springs/model.hh"

#include <Eigen/SparseCholesky>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <tuple>

namespace vtb::reproduction::parts {
using namespace vtb::harness; // the general harness: solvers, compare, sweep, metrics, tables

/// The linear static displacement of the spring network under the loads at time t:
/// K_ff u_f = f_f with K the stiffness (df/du at rest, stiffness signs) over the free nodes.
template <int dim> Nodal<dim> linear_static(const Model<dim>& model, double t) {
  const Nodal<dim> zero = Nodal<dim>::Zero(dim, model.num_nodes());
  const int nf = static_cast<int>(model.free_nodes.size());
  const Eigen::SparseMatrix<double> Kff =
      free_dof_block<dim>(Eigen::SparseMatrix<double>(-force_jacobians(model.net, zero, false).K), model);
  Nodal<dim> f(dim, model.num_nodes());
  model.external_forces(t, f);
  Eigen::VectorXd rhs(dim * nf);
  for (int i = 0; i < nf; ++i) rhs.segment<dim>(dim * i) = f.col(model.free_nodes[static_cast<std::size_t>(i)]);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Kff);
  const Eigen::VectorXd uf = ldlt.solve(rhs);
  Nodal<dim> u = zero;
  for (int i = 0; i < nf; ++i) u.col(model.free_nodes[static_cast<std::size_t>(i)]) = uf.segment<dim>(dim * i);
  return u;
}

template Nodal<2> linear_static<2>(const Model<2>&, double);
template Nodal<3> linear_static<3>(const Model<3>&, double);

namespace {

struct Case {
  const char* name;
  std::string scene; ///< TOML text; mesh paths absolute
};

std::string strip(const char* name, const char* force, const char* nu = "0.3333333333333333") {
  return std::string("[scene]\nname = \"") + name +
         "\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"rectangle\", size = [0.2, "
         "0.02], divisions = [40, 4] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " +
         nu +
         "\ndensity = 1000.0\nthickness = 0.001\n[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force "
         "= " +
         force + "\n";
}

/// Issue 25's held-out 3D family: a CGAL Mesh_3 cube of 4 cm (about 500 nodes), its bottom
/// clamped, its top loaded by `loads` (TOML [[load]] tables), at Poisson ratio `nu`.
std::string block(const char* name, const std::string& loads, const char* nu = "0.3") {
  return std::string("[scene]\nname = \"") + name +
         "\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"box\", size = [0.04, 0.04, "
         "0.04], mesher = \"cgal\", nodes = 500 }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " +
         nu + "\ndensity = 1000.0\n[[fix]]\ngroup = \"bottom\"\n" + loads;
}

/// A bar of square section (10 x 2 x 2 structured cells, two through the thickness), clamped
/// at x = 0 and bent by a transverse load on its free end: the 3D strip in bending.
std::string bar_bending(const char* name) {
  return std::string("[scene]\nname = \"") + name +
         "\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"box\", size = [0.1, 0.02, "
         "0.02], divisions = [10, 2, 2] }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = "
         "1000.0\n[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.0, 0.0, -1.0e-3]\n";
}

/// The top sheared along x.
std::string top_shear() {
  return "[[load]]\ngroup = \"top\"\ntotal_force = [0.1, 0.0, 0.0]\n";
}
/// The top pressed down.
std::string top_press() {
  return "[[load]]\ngroup = \"top\"\ntotal_force = [0.0, 0.0, -0.1]\n";
}
/// A couple about the vertical axis: the top face's strips x <= 1 cm and x >= 3 cm pushed
/// along +y and -y (a torsion test's load as uniform tractions).
std::string top_twist() {
  return "[[load]]\nbox = [[0.0, 0.0, 0.04], [0.01, 0.04, 0.04]]\ntotal_force = [0.0, 0.05, 0.0]\n"
         "[[load]]\nbox = [[0.03, 0.0, 0.04], [0.04, 0.04, 0.04]]\ntotal_force = [0.0, -0.05, 0.0]\n";
}

/// Issue 25's plate with a hole: a CGAL plate of 10 x 5 cm (600 nodes) with a central hole of
/// radius 1.2 cm, clamped on its left edge and loaded on its right edge by `force` (the stress
/// concentration of Kirsch's problem at the hole's rim), at Poisson ratio `nu`.
std::string plate_hole(const char* name, const char* force, const char* nu = "0.3") {
  return std::string("[scene]\nname = \"") + name +
         "\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = \"rectangle\", size = [0.1, "
         "0.05], mesher = \"cgal\", nodes = 600, hole = 0.012 }\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = " +
         nu + "\ndensity = 1000.0\nthickness = 0.001\n[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\n" +
         "total_force = " + force + "\n";
}

/// Cook's membrane on a structured 16 x 16 grid mapped onto the trapezoid (0,0) (48,44) (48,60)
/// (0,44): clamped at x = 0, unit shear on x = 48, E = 1, nu = 1/3 (both linear, so the size of
/// the load does not matter here).
std::string cook() {
  return "[scene]\nname = \"cook\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\ngenerate = { shape = "
         "\"rectangle\", size = [48.0, 44.0], divisions = [16, 16] }\n[material]\nyoung_modulus = 1.0\n"
         "poisson_ratio = 0.3333333333333333\ndensity = 1.0\nthickness = 1.0\n[[fix]]\ngroup = \"left\"\n"
         "[[load]]\ngroup = \"right\"\ntotal_force = [0.0, 1.0]\n";
}

/// Maps the 48 x 44 rectangle onto Cook's trapezoid: (x, y) -> (x, 44 x / 48 + y (44 - 28 x / 48) / 44).
void to_cook(Mesh<2>& mesh) {
  for (Eigen::Index v = 0; v < mesh.points.cols(); ++v) {
    const double x = mesh.points(0, v), y = mesh.points(1, v);
    mesh.points(1, v) = 44.0 * x / 48.0 + y * (44.0 - 28.0 * x / 48.0) / 44.0;
  }
}

std::string from_file(const std::filesystem::path& scenes_dir, const char* file) {
  std::ifstream f(scenes_dir / file);
  std::stringstream s;
  s << f.rdbuf();
  std::string text = s.str();
  // The scene's mesh path is relative to the scene folder: make it absolute.
  const std::string key = "file = \"";
  const auto at = text.find(key);
  if (at != std::string::npos) text.insert(at + key.size(), (scenes_dir.string() + "/"));
  return text;
}

std::string slab(const std::filesystem::path& meshes_dir) {
  return "[scene]\nname = \"slab-cantilever\"\nduration = 1.0\noutput_interval = 1.0\n[mesh]\nfile = \"" +
         (meshes_dir / "slab_500.msh").string() +
         "\"\n[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.25\ndensity = 1000.0\n[[fix]]\ngroup = "
         "\"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [0.0, 0.0, -0.001]\n";
}

/// One row per calibration: relative L2 error over all nodes against P1 on the mesh, at the
/// node of largest P1 displacement, the norms' ratio; against the continuum (the springs',
/// and P1's own, the same on every row of a case) and how converged the continuum is.
template <int dim>
void rows(const char* name, const Scene& base, const Mesh<dim>& mesh, std::ostream& os, std::ostream* log) {
  Scene fs = base;
  fs.solver.fem.static_solve = true;
  fs.solver.fem.degree = 1;
  fs.solver.fem.refinements = 0;
  const Model<dim> fem_model = build_model<dim>(fs, mesh);
  Trajectory<dim> fem;
  fem::FemOptions fo = fem::options_from(fs.solver); // the harness's run_solver steps in time; here: static
  fo.static_solve = true;
  fem::simulate<dim>(fem_model, fs.material, fo, fem, true);
  const Nodal<dim>& uf = fem.field.back();
  const auto continuum = fem::continuum_static<dim>(fem_model, fs.material);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto against_continuum = [&](const Nodal<dim>& u) {
    return continuum ? (u - continuum->u).norm() / continuum->u.norm() : nan;
  };
  if (log && continuum) *log << "[fidelity] " << name << " continuum: " << continuum->how << "\n";
  Eigen::Index peak = 0;
  uf.colwise().norm().maxCoeff(&peak);
  for (const char* springs : {"lloyd", "van-gelder", "fitted"}) {
    Scene s = base;
    s.solver.springs = springs;
    // The default springs: fitted to the continuum's answers where it is within its budget.
    const Yardstick yardstick = continuum_yardstick();
    const Model<dim> model = build_model<dim>(s, mesh, {}, false, &yardstick);
    const Nodal<dim> us = linear_static(model, model.duration);
    const double all = (us - uf).norm() / uf.norm();
    const double at_peak = (us.col(peak) - uf.col(peak)).norm() / uf.col(peak).norm();
    const double stiffness = uf.norm() / us.norm(); // > 1: springs too stiff
    if (log) *log << "[fidelity] " << name << " " << springs << ": " << all << "\n";
    os << name << ',' << dim << ',' << mesh.num_nodes() << ',' << springs << ',' << std::setprecision(5) << all << ','
       << at_peak << ',' << stiffness << ',' << model.net.calibration_seconds << ','
       << (model.net.calibration_cached ? "true" : "false") << ',' << against_continuum(us) << ','
       << against_continuum(uf) << ',' << (continuum ? continuum->refinements : -1) << ','
       << (continuum ? continuum->change : nan) << ',' << (continuum && continuum->converged ? "true" : "false")
       << '\n';
  }
}

} // namespace

void write_fidelity(const std::filesystem::path& out, const std::filesystem::path& scenes_dir, std::ostream* log) {
  const std::filesystem::path meshes_dir = scenes_dir / ".." / ".." / "meshes" / "data";
  std::ostringstream os;
  os << "case,dim,nodes,springs,displacement_error,peak_node_error,fem_over_springs_norm,calibration_seconds,"
        "calibration_cached,continuum_error,mesh_fem_continuum_error,continuum_refinements,continuum_change,"
        "continuum_converged\n";
  const std::vector<Case> cases = {{"cook", cook()},
                                   {"strip-tension", strip("strip-tension", "[1.0e-4, 0.0]")},
                                   {"strip-bending", strip("strip-bending", "[0.0, 1.0e-6]")},
                                   // Bending of parts two cells thick, where P1 on
                                   // the mesh locks: the repository's cantilever and a 3D bar.
                                   {"cantilever-2-cells", from_file(scenes_dir, "cantilever_step.toml")},
                                   {"bar-bending-3d", bar_bending("bar-bending-3d")},
                                   {"plate517-one-force", from_file(scenes_dir, "plate517_step.toml")},
                                   {"plate517-four-forces", from_file(scenes_dir, "plate517_four_forces.toml")},
                                   {"slab-cantilever", slab(meshes_dir)},
                                   // Held-out families: a clamped block in shear,
                                   // compression and torsion, and Poisson ratios off the
                                   // lattice's own (1/3 in 2D, 1/4 in 3D) in both dimensions.
                                   {"block-shear", block("block-shear", top_shear())},
                                   {"block-press", block("block-press", top_press())},
                                   {"block-twist", block("block-twist", top_twist())},
                                   {"block-shear-nu0.2", block("block-shear-nu0.2", top_shear(), "0.2")},
                                   {"block-shear-nu0.45", block("block-shear-nu0.45", top_shear(), "0.45")},
                                   {"block-press-nu0.49", block("block-press-nu0.49", top_press(), "0.49")},
                                   {"strip-tension-nu0.2", strip("strip-tension-nu0.2", "[1.0e-4, 0.0]", "0.2")},
                                   {"strip-tension-nu0.45", strip("strip-tension-nu0.45", "[1.0e-4, 0.0]", "0.45")},
                                   {"hole-tension", plate_hole("hole-tension", "[1.0e-3, 0.0]")},
                                   {"hole-shear", plate_hole("hole-shear", "[0.0, 1.0e-4]")},
                                   {"hole-tension-nu0.2", plate_hole("hole-tension-nu0.2", "[1.0e-3, 0.0]", "0.2")},
                                   {"hole-tension-nu0.45", plate_hole("hole-tension-nu0.45", "[1.0e-3, 0.0]", "0.45")}};
  for (const auto& c : cases) {
    const Scene scene = parse_scene(c.scene, std::string(c.name) + ".toml", scenes_dir);
    AnyMesh mesh_of_case = load_mesh(scene);
    std::visit(
        [&](auto& mesh) {
          if constexpr (std::decay_t<decltype(mesh)>::points_dim == 2)
            if (std::string(c.name) == "cook") to_cook(mesh);
          rows(c.name, scene, mesh, os, log);
        },
        mesh_of_case);
  }
  write_files_atomically(out, {{"fidelity.csv", os.str()}});
}

namespace {

std::string block_scene(const std::filesystem::path& mesh, double nu) {
  std::ostringstream os;
  os << std::setprecision(17) << R"([scene]
name = "deep-press"
duration = 1.0
output_interval = 0.1
[mesh]
file = ")"
     << mesh.string() << R"("
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
kind = ")"
     << solvers::kImplicitEuler << R"("
dt = 0.02
springs = "fitted"
)";
  // "fitted": the paper's pair network, fitted as auto builds it under light loads; auto itself
  // builds the volume network under this press (docs/volume_term.md, "What auto builds"), whose
  // row is springs-fitted-nodal.
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
    const Scene g =
        parse_scene(R"([scene]
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [0.04, 0.04, )" +
                        std::to_string(kDeepPressH) + "], mesher = \"cgal\", nodes = " + std::to_string(nodes) + R"( }
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
  os << std::setprecision(6) << "poisson_ratio,model,nodes,level,force,depth,depth_ratio,converged,inverted_cells\n";
  auto mark = std::chrono::steady_clock::now();
  const auto seconds = [&mark] { // since the last call
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return std::round(10 * s) / 10;
  };
  // The fitted networks trained on the continuum, as vtb run builds them (P1 on this layer is
  // 37-58 % stiffer than P2 at 10 % depth: a fit to it inherits its locking).
  const Yardstick yardstick = continuum_yardstick();
  for (const double nu : {0.3, 0.45}) {
    const Scene scene = parse_scene(block_scene(mesh, nu), "deep_press.toml", out);
    const Model<3> model = build_model<3>(scene, std::get<Mesh3>(load_mesh(scene)), {}, false, &yardstick);
    const auto depth = [](const Trajectory<3>& tr, std::size_t k) { return -tr.probe_u.at(k).at(0).z(); };
    // inverted: the springs' most cells at J <= 0 at once over the run (summary.json's
    // inverted_cells); NaN for the continua.
    const auto row = [&](const std::string& name, double level, double force, double d, bool converged,
                         double inverted = std::nan("")) {
      os << nu << ',' << name << ',' << model.num_nodes() << ',' << level << ',' << force << ',' << d << ','
         << d / kDeepPressH << ',' << (converged ? "true" : "false") << ',' << inverted << '\n';
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
    // How converged the neo-Hookean reference is: P2 refined once, one static solve at 0.5 F30
    // (about 16 % deep; a path refined once costs 8x the dofs at every level), beside the path's
    // P2 on the mesh at that level. At F30 one refinement moved it by a fifth (docs/fem.md).
    {
      fem::FemOptions refined;
      refined.static_solve = true;
      refined.degree = 2;
      refined.refinements = 1;
      refined.kinematics = fem::Kinematics::neo_hookean;
      Trajectory<3> tr;
      fem::simulate<3>(scaled(static_cast<const Problem<3>&>(model), 0.5 * f30), scene.material, refined, tr);
      const double d = depth(tr, tr.t.size() - 1);
      row("neo-hookean-p2-refined", 0.5, 0.5 * f30, d, std::isfinite(d));
      if (log)
        *log << "  nu " << nu << ": neo-hookean-p2 refined once at 0.5 F30 in " << seconds() << " s\n" << std::flush;
    }
    // The springs at rest under each level (at twice the continua's, for they soften early):
    // implicit Euler through the scene's 0.3 s ramp to 2 s; at rest when the last two samples
    // (0.1 s apart) agree to 1e-3. The paper's pair network ("springs": the fitted springs, named
    // in the scene) and beside it the networks with the volume term per cell
    // (docs/volume_term.md): "springs-volume" (springs = "volume", the element fit) and
    // "springs-fitted-volume" (springs = "fitted-volume", fitted as the pair springs are) and
    // "springs-fitted-stable" (springs = "fitted-stable": the same with the stable energy's shear
    // part in every cell), with their inverted cells; and "springs-nodal-volume" (springs =
    // "nodal-volume": the element fit's constants, the volume averaged per node) and
    // "springs-fitted-nodal" (springs = "fitted-nodal": the stable cells' shear part, the volume
    // averaged per node, fitted as the pair springs are).
    Scene with_volume = scene, with_nodal_volume = scene, with_fitted_volume = scene, with_fitted_stable = scene,
          with_fitted_nodal = scene;
    with_volume.solver.springs = "volume";
    with_nodal_volume.solver.springs = "nodal-volume";
    with_fitted_nodal.solver.springs = "fitted-nodal";
    with_fitted_volume.solver.springs = "fitted-volume";
    with_fitted_stable.solver.springs = "fitted-stable";
    const Model<3> volume_model = build_model<3>(with_volume, std::get<Mesh3>(load_mesh(scene)), {}, false);
    const Model<3> nodal_volume_model = build_model<3>(with_nodal_volume, std::get<Mesh3>(load_mesh(scene)), {}, false);
    const Model<3> fitted_volume_model =
        build_model<3>(with_fitted_volume, std::get<Mesh3>(load_mesh(scene)), {}, false, &yardstick);
    const Model<3> fitted_stable_model =
        build_model<3>(with_fitted_stable, std::get<Mesh3>(load_mesh(scene)), {}, false, &yardstick);
    const Model<3> fitted_nodal_model =
        build_model<3>(with_fitted_nodal, std::get<Mesh3>(load_mesh(scene)), {}, false, &yardstick);
    using Entry = std::tuple<const char*, const Scene*, const Model<3>*>;
    for (const auto& [name, springs, spring_model] :
         {Entry{"springs", &scene, &model}, Entry{"springs-volume", &with_volume, &volume_model},
          Entry{"springs-nodal-volume", &with_nodal_volume, &nodal_volume_model},
          Entry{"springs-fitted-volume", &with_fitted_volume, &fitted_volume_model},
          Entry{"springs-fitted-stable", &with_fitted_stable, &fitted_stable_model},
          Entry{"springs-fitted-nodal", &with_fitted_nodal, &fitted_nodal_model}}) {
      for (int k = 1; k <= 2 * steps; ++k) {
        const double level = 1.0 * k / steps;
        Model<3> loaded = scaled(*spring_model, level * f30);
        loaded.duration = 2.0;
        Trajectory<3> tr;
        const RunReport r = run_solver<3>(*springs, loaded, solvers::kImplicitEuler, 0, tr);
        const std::size_t last = tr.t.size() - 1;
        const double d = r.stable ? depth(tr, last) : std::nan("");
        double inverted = std::nan("");
        for (const auto& [key, value] : r.extra)
          if (key == "inverted_cells") inverted = value;
        row(name, level, level * f30, d, r.stable && std::abs(d - depth(tr, last - 1)) <= 1e-3 * std::abs(d), inverted);
      }
      if (log) *log << "  nu " << nu << ": " << name << " in " << seconds() << " s\n" << std::flush;
    }
  }
  std::filesystem::remove(mesh);
  write_files_atomically(out, {{"deep_press.csv", os.str()}});
}

} // namespace vtb::reproduction::parts
