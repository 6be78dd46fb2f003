#include "vtb/problem/scene.hh"

#include "scene_reader.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/problem/solver_registry.hh"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace vtb {
namespace {

using detail::non_negative;
using detail::positive;
using detail::TableReader;

/// Reads the region keys (box | group | point; disc for a load) of a fix, load, drive entry.
RegionDesc read_region(const TableReader& r, std::string label, bool loads = false) {
  RegionDesc d;
  d.label = std::move(label);
  int count = 0;
  if (r.has("box")) {
    ++count;
    const toml::array* a = r.node("box")->as_array();
    if (!a || a->size() != 2 || !a->get(0)->is_array() || !a->get(1)->is_array())
      r.fail("box", "must be [[min...], [max...]]");
    auto corner = [&](std::size_t i) {
      const toml::array& c = *a->get(i)->as_array();
      if (c.size() < 2 || c.size() > 3) r.fail("box", "corners must have 2 or 3 coordinates");
      Eigen::VectorXd v(static_cast<Eigen::Index>(c.size()));
      for (std::size_t k = 0; k < c.size(); ++k) {
        const auto x = c.get(k)->value<double>();
        if (!x || !std::isfinite(*x)) r.fail("box", "corner coordinates must be finite numbers");
        v[static_cast<Eigen::Index>(k)] = *x;
      }
      return v;
    };
    Eigen::VectorXd lo = corner(0), hi = corner(1);
    if (lo.size() != hi.size()) r.fail("box", "min and max corners differ in dimension");
    if ((lo.array() > hi.array()).any()) r.fail("box", "min corner exceeds max corner");
    d.box = std::make_pair(lo, hi);
  }
  if (r.has("group")) {
    ++count;
    d.group = r.string("group", std::nullopt);
    if (d.group.empty()) r.fail("group", "must not be empty");
  }
  if (r.has("point")) {
    ++count;
    d.point = r.vector("point", 2, 3);
  }
  if (loads && r.has("disc")) {
    ++count;
    const toml::table* t = r.table("disc");
    const TableReader dr(*t, r.path() + ".disc", r.file(), {"center", "radius"});
    d.disc = std::make_pair(dr.vector("center", 2, 3), dr.number("radius", std::nullopt, positive));
  }
  if (count != 1)
    r.fail("", "needs exactly one of box, group, point" + std::string(loads ? ", disc" : "") + " (has " +
                   std::to_string(count) + ")");
  return d;
}

std::string check_poisson(double v) {
  return (v >= 0.0 && v < 0.5) ? "" : "must be in [0, 0.5)";
}

} // namespace

namespace {

void read_scene_table(const TableReader& top, const std::string& name, Scene& s) {
  const toml::table* t = top.table("scene");
  if (!t) top.fail("scene", "missing (required table)");
  {
    const TableReader r(*t, "[scene]", name, {"name", "duration", "output_interval"});
    s.name = r.string("name", std::string("scene"));
    s.duration = r.number("duration", std::nullopt, positive);
    s.output_interval = r.number("output_interval", std::nullopt, positive);
    if (s.output_interval > s.duration) r.fail("output_interval", "must not exceed [scene].duration");
  }
}

/// `refine = { center, radius, size, growth }` or an array of them (cgal_generate.hh, Refinement).
std::vector<Refinement> read_refine(const TableReader& gr, const std::string& name) {
  std::vector<const toml::table*> list;
  if (!gr.has("refine")) return {};
  if (gr.node("refine")->is_table())
    list.push_back(gr.table("refine"));
  else
    list = gr.tables("refine");
  if (list.empty()) gr.fail("refine", "must be a table { center, radius, size } or an array of them");
  std::vector<Refinement> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const TableReader rr(*list[i], "[mesh].generate.refine[" + std::to_string(i) + "]", name,
                         {"center", "radius", "size", "growth"});
    Refinement ref;
    ref.center = rr.vector("center", 3, 3);
    ref.radius = rr.number("radius", std::nullopt, non_negative);
    ref.size = rr.number("size", std::nullopt, positive);
    ref.growth = rr.number("growth", kRefineGrowth, growth_error);
    out.push_back(ref);
  }
  return out;
}

/// shape = "surface": a closed surface file meshed by CGAL (docs/meshes.md).
void read_surface_generate(const TableReader& gr, const std::filesystem::path& base_dir, MeshDesc& m) {
  for (const char* key : {"size", "divisions", "hole"})
    if (gr.has(key)) gr.fail(key, "is not for shape = \"surface\" (give nodes or cell_size)");
  m.mesher = gr.string("mesher", "cgal", {"cgal"});
  m.file = base_dir / gr.string("file", std::nullopt);
  if (gr.has("nodes") == gr.has("cell_size")) gr.fail("", "shape = \"surface\" needs exactly one of nodes, cell_size");
  if (gr.has("nodes")) m.nodes = gr.integer("nodes", std::nullopt, 50, 500'000);
  if (gr.has("cell_size")) m.cell_size = gr.number("cell_size", std::nullopt, positive);
  m.scale = gr.number("scale", 1.0, positive);
  m.refine = read_refine(gr, gr.file());
}

/// shape = "rectangle" | "box": structured, or unstructured by CGAL.
void read_shape_generate(const TableReader& gr, MeshDesc& m) {
  for (const char* key : {"file", "cell_size", "scale"})
    if (gr.has(key)) gr.fail(key, "is for shape = \"surface\"");
  const std::size_t d = m.shape == "rectangle" ? 2 : 3;
  m.size = gr.vector("size", d, d);
  if ((m.size.array() <= 0).any()) gr.fail("size", "entries must be > 0");
  m.mesher = gr.string("mesher", "structured", {"structured", "cgal"});
  if (gr.has("refine") && !(d == 3 && m.mesher == "cgal"))
    gr.fail("refine", "is for a CGAL box (mesher = \"cgal\") or a surface");
  if (m.mesher == "cgal") {
    if (gr.has("divisions")) gr.fail("divisions", "is for mesher = \"structured\"; a CGAL mesh takes nodes");
    m.nodes = gr.integer("nodes", std::nullopt, d == 2 ? 4 : 50, 500'000);
    m.refine = read_refine(gr, gr.file());
    if (gr.has("hole")) {
      if (d != 2) gr.fail("hole", "is for shape = \"rectangle\" (a plate with a hole)");
      m.hole = gr.number("hole", std::nullopt, positive);
      if (const std::string why = hole_error(m.hole, m.size.minCoeff()); !why.empty()) gr.fail("hole", why);
    }
  } else {
    if (gr.has("hole")) gr.fail("hole", "is for mesher = \"cgal\" (a structured mesh has no hole)");
    if (gr.has("nodes")) gr.fail("nodes", "is for mesher = \"cgal\"; a structured mesh takes divisions");
    const Eigen::VectorXd div = gr.vector("divisions", d, d);
    // Checked before the cast: a double beyond int's range does not convert (found by fuzzing).
    if ((div.array() != div.array().round()).any() || (div.array() < 1).any() || (div.array() > 2000).any())
      gr.fail("divisions", "entries must be whole numbers in [1, 2000]");
    m.divisions = div.cast<int>();
  }
}

void read_mesh(const TableReader& top, const std::string& name, const std::filesystem::path& base_dir, Scene& s) {
  const toml::table* t = top.table("mesh");
  if (!t) top.fail("mesh", "missing (required table)");
  {
    const TableReader r(*t, "[mesh]", name, {"file", "generate"});
    if (r.has("file") == r.has("generate")) r.fail("", "needs exactly one of file, generate");
    if (r.has("file")) {
      s.mesh.file = base_dir / r.string("file", std::nullopt);
    } else {
      const toml::table* g = r.table("generate");
      const TableReader gr(
          *g, "[mesh].generate", name,
          {"shape", "size", "divisions", "mesher", "nodes", "hole", "file", "cell_size", "scale", "refine"});
      s.mesh.shape = gr.string("shape", std::nullopt, {"rectangle", "box", "surface"});
      if (s.mesh.shape == "surface")
        read_surface_generate(gr, base_dir, s.mesh);
      else
        read_shape_generate(gr, s.mesh);
    }
  }
}

void read_material(const TableReader& top, const std::string& name, Scene& s) {
  const toml::table* t = top.table("material");
  if (!t) top.fail("material", "missing (required table)");
  {
    const TableReader r(*t, "[material]", name,
                        {"young_modulus", "poisson_ratio", "density", "thickness", "retardation_time", "mass_damping"});
    s.material.young_modulus = r.number("young_modulus", std::nullopt, positive);
    s.material.poisson_ratio = r.number("poisson_ratio", std::nullopt, check_poisson);
    s.material.density = r.number("density", std::nullopt, positive);
    s.material.thickness = r.number("thickness", 1.0, positive);
    s.material.retardation_time = r.number("retardation_time", 0.0, non_negative);
    s.material.mass_damping = r.number("mass_damping", 0.0, non_negative);
  }
}

void read_regions(const TableReader& top, const std::string& name, Scene& s) {
  auto label = [](const TableReader& r, const char* kind, std::size_t i) {
    return r.has("name") ? r.string("name", std::nullopt) : std::string(kind) + "[" + std::to_string(i) + "]";
  };
  const auto fixes = top.tables("fix");
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    const TableReader r(*fixes[i], "[[fix]] #" + std::to_string(i + 1), name, {"box", "group", "point", "name"});
    s.fixes.push_back({read_region(r, label(r, "fix", i))});
  }
  const auto loads = top.tables("load");
  for (std::size_t i = 0; i < loads.size(); ++i) {
    const TableReader r(*loads[i], "[[load]] #" + std::to_string(i + 1), name,
                        {"box", "group", "point", "disc", "name", "total_force", "start", "ramp"});
    LoadDesc l;
    l.region = read_region(r, label(r, "load", i), true);
    l.total_force = r.vector("total_force", 2, 3);
    l.start = r.number("start", 0.0, non_negative);
    l.ramp = r.number("ramp", 0.0, non_negative);
    s.loads.push_back(std::move(l));
  }
  const auto drives = top.tables("drive");
  for (std::size_t i = 0; i < drives.size(); ++i) {
    const TableReader r(*drives[i], "[[drive]] #" + std::to_string(i + 1), name,
                        {"box", "group", "point", "name", "displacement", "start", "ramp"});
    DriveDesc d;
    d.region = read_region(r, label(r, "drive", i));
    d.displacement = r.vector("displacement", 2, 3);
    d.start = r.number("start", 0.0, non_negative);
    d.ramp = r.number("ramp", 0.0, non_negative);
    s.drives.push_back(std::move(d));
  }
}

void read_initial(const TableReader& top, const std::string& name, Scene& s) {
  if (const toml::table* t = top.table("initial")) {
    const TableReader r(*t, "[initial]", name, {"velocity", "angular_velocity"});
    if (r.has("velocity")) s.initial_velocity = r.vector("velocity", 2, 3);
    if (r.has("angular_velocity")) {
      if (r.node("angular_velocity")->is_number())
        s.initial_angular_velocity = Eigen::VectorXd::Constant(1, r.number("angular_velocity", std::nullopt));
      else
        s.initial_angular_velocity = r.vector("angular_velocity", 3, 3);
    }
  }
}

void read_probes(const TableReader& top, const std::string& name, Scene& s) {
  const auto probes = top.tables("probe");
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const TableReader r(*probes[i], "[[probe]] #" + std::to_string(i + 1), name, {"name", "point", "load"});
    ProbeDesc p;
    p.name = r.string("name", "probe" + std::to_string(i));
    if (r.has("point") == r.has("load")) r.fail("", "needs exactly one of point, load");
    if (r.has("load"))
      p.load = r.string("load", std::nullopt);
    else
      p.point = r.vector("point", 2, 3);
    for (const auto& q : s.probes)
      if (q.name == p.name) r.fail("name", "probe name \"" + p.name + "\" is used twice");
    s.probes.push_back(std::move(p));
  }
}

void read_solver(const TableReader& top, const std::string& name, Scene& s) {
  if (const toml::table* t = top.table("solver")) {
    const TableReader r(*t, "[solver]", name,
                        {"kind", "dt", "filter", "momentum_correction", "strain_limit", "step_budget", "springs",
                         "rtol", "atol", "linear_solver", "cg_tolerance", "degree", "refinements", "scheme", "static",
                         "static_path", "kinematics"});
    std::vector<std::string_view> kinds;
    for (const auto& e : solvers::kEntries)
      if (e.scene_kind) kinds.emplace_back(e.name);
    const SolverDesc d; // the defaults
    SolverDesc& o = s.solver;
    o.kind = r.string("kind", d.kind, kinds);
    o.dt = r.number("dt", d.dt, positive);
    o.dt_given = r.node("dt") != nullptr;
    o.springs = r.string("springs", d.springs,
                         {"auto", "lloyd", "van-gelder", "fitted", "volume", "nodal-volume", "fitted-volume",
                          "fitted-stable", "fitted-nodal"});
    o.step.filter = r.string("filter", d.step.filter, {solvers::kFilterChoices.begin(), solvers::kFilterChoices.end()});
    o.step.momentum_correction = r.boolean("momentum_correction", d.step.momentum_correction);
    o.step.strain_limit = r.number("strain_limit", d.step.strain_limit, non_negative);
    o.step.step_budget = r.number("step_budget", d.step.step_budget, non_negative);
    o.step.linear_solver = r.string("linear_solver", d.step.linear_solver, {"auto", "direct", "cg", "cg-multigrid"});
    o.step.cg_tolerance = r.number("cg_tolerance", d.step.cg_tolerance, positive);
    if (o.step.cg_tolerance >= 1) r.fail("cg_tolerance", "must be below 1");
    o.cvode.rtol = r.number("rtol", d.cvode.rtol, positive);
    o.cvode.atol = r.number("atol", d.cvode.atol, positive);
    o.fem.degree = r.integer("degree", d.fem.degree, 1, 2);
    o.fem.refinements = r.integer("refinements", d.fem.refinements, 0, 6);
    o.fem.scheme = r.string("scheme", d.fem.scheme, {"generalized-alpha", "newmark", "backward-euler"});
    o.fem.static_solve = r.boolean("static", d.fem.static_solve);
    o.fem.static_path = r.boolean("static_path", d.fem.static_path);
    if (o.fem.static_path && !o.fem.static_solve) r.fail("static_path", "needs static = true");
    const std::string law =
        r.string("kinematics", kinematics_name(d.fem.kinematics), {kKinematics.begin(), kKinematics.end()});
    o.fem.kinematics = *kinematics_named(law); // r.string admitted only kKinematics' names
    // Nonlinear kinematics step with backward Euler: its default when no scheme is named.
    if (o.fem.nonlinear() && !r.node("scheme")) o.fem.scheme = "backward-euler";
    if (s.solver.dt > s.duration) r.fail("dt", "must not exceed [scene].duration");
  }
}

/// One scripted hand: [haptics.hand] or a [[haptics.probe]].
HandDesc read_hand(const toml::table& ht, const std::string& path, const std::string& name) {
  const TableReader hr(ht, path, name, {"waypoints", "duration", "grip_stiffness"});
  HandDesc hand;
  const toml::array* w = hr.node("waypoints") ? hr.node("waypoints")->as_array() : nullptr;
  if (!w || w->empty()) hr.fail("waypoints", "must be a non-empty array of [x, y] points");
  for (std::size_t i = 0; i < w->size(); ++i) {
    const toml::array* p = w->get(i)->as_array();
    if (!p || p->size() < 2 || p->size() > 3)
      hr.fail("waypoints",
              "entry " + std::to_string(i) + " must be [x, y] (device) or [x, y, z] (a point of a 3D scene)");
    if (i > 0 && static_cast<Eigen::Index>(p->size()) != hand.waypoints.front().size())
      hr.fail("waypoints", "entry " + std::to_string(i) + " has " + std::to_string(p->size()) +
                               " coordinates, entry 0 has " + std::to_string(hand.waypoints.front().size()));
    Eigen::VectorXd q(static_cast<Eigen::Index>(p->size()));
    for (std::size_t k = 0; k < p->size(); ++k) {
      const auto x = p->get(k)->value<double>();
      if (!x || !std::isfinite(*x)) hr.fail("waypoints", "entry " + std::to_string(i) + " must hold finite numbers");
      q[static_cast<Eigen::Index>(k)] = *x;
    }
    hand.waypoints.push_back(q);
  }
  hand.duration = hr.number("duration", std::nullopt, positive);
  hand.grip_stiffness = hr.number("grip_stiffness", std::nullopt, positive);
  return hand;
}

/// [haptics.plane]: where a 3D scene puts the 2-DOF device (orthonormal axes).
DevicePlaneDesc read_plane(const toml::table& pt, const std::string& name) {
  const TableReader pr(pt, "[haptics.plane]", name, {"origin", "x_axis", "y_axis"});
  DevicePlaneDesc plane;
  const auto vec3 = [&pr](std::string_view key, const Eigen::Vector3d& fallback) -> Eigen::Vector3d {
    if (!pr.has(key)) return fallback;
    const Eigen::VectorXd v = pr.vector(key, 3, 3);
    return v;
  };
  plane.origin = vec3("origin", plane.origin);
  plane.x_axis = vec3("x_axis", plane.x_axis);
  plane.y_axis = vec3("y_axis", plane.y_axis);
  for (auto [key, axis] : {std::pair{"x_axis", &plane.x_axis}, std::pair{"y_axis", &plane.y_axis}}) {
    if (!(axis->norm() > 1e-12)) pr.fail(key, "must be a non-zero direction");
    axis->normalize();
  }
  if (std::abs(plane.x_axis.dot(plane.y_axis)) > 1e-6)
    pr.fail("y_axis", "must be orthogonal to x_axis (the device's two axes are at right angles)");
  return plane;
}

void read_haptics(const TableReader& top, const std::string& name, const std::filesystem::path& base_dir, Scene& s) {
  const toml::table* t = top.table("haptics");
  if (!t) return;
  {
    const TableReader r(*t, "[haptics]", name,
                        {"device", "plugin", "plugin_config", "address", "link_watchdog", "rate", "coupling_stiffness",
                         "coupling_damping", "max_force", "tip_radius", "hand", "probe", "plane"});
    HapticsDesc h;
    h.device = r.string("device", "procat-sim", {"procat-sim", "replay", "null", "plugin", "udp"});
    if (r.has("plugin")) h.plugin = base_dir / r.string("plugin", std::nullopt);
    if (h.device == "plugin" && h.plugin.empty())
      r.fail("plugin", "device = \"plugin\" needs plugin = \"PATH\" (the driver's shared library)");
    h.plugin_config = r.string("plugin_config", "");
    h.address = r.string("address", "127.0.0.1:47000");
    h.link_watchdog = r.number("link_watchdog", 0.05, positive);
    h.rate = r.number("rate", 1000.0, positive);
    h.coupling_stiffness = r.number("coupling_stiffness", 400.0, positive);
    h.coupling_damping = r.number("coupling_damping", 2.0, non_negative);
    h.max_force = r.number("max_force", 4.0, positive);
    if (r.has("tip_radius")) h.tip_radius = r.number("tip_radius", 0.0, non_negative);
    if (const toml::table* ht = r.table("hand")) h.hand = read_hand(*ht, "[haptics.hand]", name);
    const auto hands = r.tables("probe");
    for (std::size_t i = 0; i < hands.size(); ++i)
      h.probes.push_back(read_hand(*hands[i], "[[haptics.probe]] #" + std::to_string(i + 1), name));
    if (!hands.empty() && h.device == "procat-sim" && !h.hand)
      r.fail("probe", "[[haptics.probe]] adds devices to the first one: [haptics.hand] is missing");
    if (const toml::table* pt = r.table("plane")) h.plane = read_plane(*pt, name);
    s.haptics = std::move(h);
  }
}

} // namespace

Scene parse_scene(std::string_view text, const std::string& name, const std::filesystem::path& base_dir) {
  toml::table root;
  try {
    root = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    throw InputError(name + ":" + std::to_string(e.source().begin.line) +
                     ": TOML syntax: " + std::string(e.description()));
  }
  Scene s;
  s.file = name;
  const TableReader top(root, "", name,
                        {"scene", "mesh", "material", "fix", "load", "drive", "initial", "probe", "solver", "haptics"});
  read_scene_table(top, name, s);
  read_mesh(top, name, base_dir, s);
  read_material(top, name, s);
  read_regions(top, name, s);
  read_initial(top, name, s);
  read_probes(top, name, s);
  read_solver(top, name, s); // after [scene]: dt is checked against the duration
  read_haptics(top, name, base_dir, s);
  return s;
}

Scene read_scene(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open scene file");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  if (s.size() > (std::size_t{16} << 20)) throw InputError(file.string() + ": scene file larger than 16 MiB");
  return parse_scene(s, file.string(), file.parent_path());
}

} // namespace vtb
