#include "vtb/problem/problem.hh"

#include "vtb/meshes/generate.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/surface.hh"
#endif
#include "vtb/meshes/msh_io.hh"

#include <Eigen/Geometry>
#include <algorithm>
#include <set>
#include <sstream>

namespace vtb {

template <int dim> void Problem<dim>::external_forces(double t, Nodal<dim>& f) const {
  f.setZero();
  for (const auto& l : loads) {
    const double s = ramp_factor(t, l.start, l.ramp);
    if (s == 0) continue;
    for (std::size_t a = 0; a < l.nodes.size(); ++a) f.col(l.nodes[a]) += s * l.force.col(static_cast<Eigen::Index>(a));
  }
}

template <int dim> void Problem<dim>::apply_constraints(double t, Nodal<dim>& u, Nodal<dim>& v) const {
  for (const auto& s : supports) {
    const Vec<dim> d = s.driven ? Vec<dim>(ramp_factor(t, s.start, s.ramp) * s.displacement) : Vec<dim>::Zero();
    const Vec<dim> dv = s.driven ? Vec<dim>(ramp_rate(t, s.start, s.ramp) * s.displacement) : Vec<dim>::Zero();
    for (int i : s.nodes) {
      u.col(i) = d;
      v.col(i) = dv;
    }
  }
}

namespace {

template <int dim> Vec<dim> as_vec(const Eigen::VectorXd& v, const std::string& what, const std::string& file) {
  if (v.size() != dim)
    throw InputError(file + ": " + what + " has " + std::to_string(v.size()) + " components; the mesh is " +
                     std::to_string(dim) + "D");
  return v;
}

/// The distance from a scene point to the node it is snapped to; InputError naming `what`
/// and the distance when it exceeds the mesh's longest edge (a typo in a coordinate, or the
/// wrong units, rather than a point on the body).
template <int dim>
double snap_distance(const Mesh<dim>& mesh, double longest, const Vec<dim>& x, int node, const std::string& what,
                     const std::string& file) {
  const double d = (mesh.points.col(node) - x).norm();
  if (d > longest) {
    std::ostringstream os;
    os << file << ": " << what << ".point is " << d << " m from the mesh (nearest node " << node << " at [";
    for (int a = 0; a < dim; ++a) os << (a ? ", " : "") << mesh.points(a, node);
    os << "]); a point must lie within the longest edge (" << longest << " m) of a node";
    throw InputError(os.str());
  }
  return d;
}

/// `longest` is the mesh's longest edge (the longest spring's rest length).
template <int dim>
Selection<dim> resolve(const Mesh<dim>& mesh, double longest, const RegionDesc& r, const std::string& file) {
  RegionSpec<dim> spec;
  const std::string what = file + ": " + r.label;
  if (r.box)
    spec.box =
        Box<dim>{as_vec<dim>(r.box->first, r.label + ".box", file), as_vec<dim>(r.box->second, r.label + ".box", file)};
  spec.group = r.group;
  if (r.point) spec.point = as_vec<dim>(*r.point, r.label + ".point", file);
  if (r.disc) spec.disc = Disc<dim>{as_vec<dim>(r.disc->first, r.label + ".disc.center", file), r.disc->second};
  Selection<dim> s = select(mesh, spec, what);
  if (s.nodes.empty()) throw InputError(what + ": the region selects no node of mesh " + mesh.source);
  if (spec.point) snap_distance(mesh, longest, *spec.point, s.nodes.front(), r.label, file);
  return s;
}

} // namespace

AnyMesh load_mesh(const Scene& scene) {
  const auto& m = scene.mesh;
  if (!m.generated()) {
    try {
      return read_msh(m.file);
    } catch (const InputError& e) {
      throw InputError(scene.file.string() + ": [mesh].file: " + e.what());
    }
  }
  if (m.mesher == "cgal") {
#ifdef VTB_HAVE_CGAL_MESHERS
    try {
      if (m.shape == "rectangle") return mesh_rectangle(m.size, m.nodes, m.hole);
      if (m.shape == "surface")
        return mesh_surface(read_surface(m.file, m.scale), m.nodes, m.cell_size, m.refine, m.file.filename().string());
      return mesh_box(m.size, m.nodes, m.refine);
    } catch (const InputError& e) {
      throw InputError(scene.file.string() + ": [mesh].generate: " + e.what());
    }
#else
    throw InputError(scene.file.string() + ": [mesh].generate (shape \"" + m.shape +
                     "\", CGAL): this build has no CGAL meshers");
#endif
  }
  if (m.shape == "rectangle") return generate_rectangle(m.size, m.divisions);
  return generate_box(m.size, m.divisions);
}

/// The longest edge of the mesh: how far a scene point may lie from the node it snaps to.
template <int dim> double longest_edge(const Mesh<dim>& mesh) {
  double longest = 0;
  for (const auto& c : mesh.cells)
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b)
        longest = std::max(longest, (mesh.points.col(c[a]) - mesh.points.col(c[b])).norm());
  return longest;
}

/// The centre of mass of a uniform body: each cell's measure shared equally by its vertices
/// (the lumping of every model here), so the spin of [initial].angular_velocity is about it.
template <int dim> Vec<dim> centre_of_mass(const Mesh<dim>& mesh) {
  Vec<dim> sum = Vec<dim>::Zero();
  double total = 0;
  for (const auto& c : mesh.cells) {
    Mat<dim> edges;
    for (int a = 0; a < dim; ++a) edges.col(a) = mesh.points.col(c[a + 1]) - mesh.points.col(c[0]);
    const double measure = std::abs(edges.determinant());
    for (int v : c) sum += measure * mesh.points.col(v);
    total += measure * (dim + 1);
  }
  return total > 0 ? Vec<dim>(sum / total) : Vec<dim>::Zero();
}

/// Fixes and drives: their nodes (and facets, for higher-order FEM), marked constrained; a
/// node may sit in two fixes but in no drive shared with anything.
template <int dim>
void resolve_supports(const Scene& scene, const Mesh<dim>& mesh, double longest, const std::string& file,
                      Problem<dim>& model) {
  const int n = mesh.num_nodes();
  model.constrained.assign(static_cast<std::size_t>(n), 0);
  // A node may sit in two fixes (both hold it at zero) but in no drive shared with anything.
  std::vector<int> owner(static_cast<std::size_t>(n), -1);
  auto claim = [&](int idx) {
    const Support<dim>& s = model.supports[static_cast<std::size_t>(idx)];
    for (int i : s.nodes) {
      int& o = owner[static_cast<std::size_t>(i)];
      if (o >= 0 && (s.driven || model.supports[static_cast<std::size_t>(o)].driven)) {
        std::string at;
        for (int a = 0; a < dim; ++a) at += (a ? ", " : "") + std::to_string(mesh.points(a, i));
        throw InputError(file + ": " + s.name + " and " + model.supports[static_cast<std::size_t>(o)].name +
                         " both constrain node " + std::to_string(i) + " at (" + at + ")");
      }
      o = idx;
      model.constrained[static_cast<std::size_t>(i)] = 1;
    }
  };
  const auto support_of = [&](const RegionDesc& region) {
    Support<dim> s;
    s.name = region.label;
    Selection<dim> sel = resolve(mesh, longest, region, file);
    s.nodes = std::move(sel.nodes);
    s.facets = std::move(sel.facets);
    if (region.box)
      s.box = Box<dim>{as_vec<dim>(region.box->first, "", file), as_vec<dim>(region.box->second, "", file)};
    return s;
  };
  for (const auto& f : scene.fixes) {
    model.supports.push_back(support_of(f.region));
    claim(static_cast<int>(model.supports.size()) - 1);
  }
  for (const auto& d : scene.drives) {
    Support<dim> s = support_of(d.region);
    s.driven = true;
    s.displacement = as_vec<dim>(d.displacement, d.region.label + ".displacement", file);
    s.start = d.start;
    s.ramp = d.ramp;
    model.supports.push_back(s);
    claim(static_cast<int>(model.supports.size()) - 1);
  }
}

/// Loads: a uniform traction lumped onto the loaded facets' vertices, or a point force shared
/// by the region's nodes.
template <int dim>
void resolve_loads(const Scene& scene, const Mesh<dim>& mesh, double longest, const std::string& file,
                   Problem<dim>& model) {
  for (const auto& l : scene.loads) {
    const Selection<dim> sel = resolve(mesh, longest, l.region, file);
    const Vec<dim> total = as_vec<dim>(l.total_force, l.region.label + ".total_force", file);
    Load<dim> load;
    load.name = l.region.label;
    load.start = l.start;
    load.ramp = l.ramp;
    load.nodes = sel.nodes;
    load.total = total;
    load.force = Nodal<dim>::Zero(dim, static_cast<Eigen::Index>(sel.nodes.size()));
    auto slot = [&](int node) {
      return static_cast<Eigen::Index>(std::lower_bound(sel.nodes.begin(), sel.nodes.end(), node) - sel.nodes.begin());
    };
    double measure = 0;
    for (const auto& f : sel.facets) measure += facet_measure(mesh, f);
    if (!sel.facets.empty() && measure > 0) {
      load.facets = sel.facets;
      // Uniform traction: each facet carries total * |facet| / |region|, split equally
      // among its vertices (exact lumping of a constant traction on linear facets).
      for (const auto& f : sel.facets) {
        const Vec<dim> share = total * (facet_measure(mesh, f) / measure) / dim;
        for (int v : f) load.force.col(slot(v)) += share;
      }
      // Nodes inside the box but on no loaded facet carry nothing: drop them.
      std::vector<int> keep;
      Nodal<dim> kept(dim, 0);
      std::vector<Vec<dim>> cols;
      for (std::size_t a = 0; a < load.nodes.size(); ++a)
        if (load.force.col(static_cast<Eigen::Index>(a)).squaredNorm() > 0) {
          keep.push_back(load.nodes[a]);
          cols.push_back(load.force.col(static_cast<Eigen::Index>(a)));
        }
      load.nodes = keep;
      load.force.resize(dim, static_cast<Eigen::Index>(cols.size()));
      for (std::size_t a = 0; a < cols.size(); ++a) load.force.col(static_cast<Eigen::Index>(a)) = cols[a];
    } else {
      // A point, or a region with no boundary facet: the force is shared equally by its nodes.
      load.force.colwise() = total / static_cast<double>(sel.nodes.size());
    }
    model.loads.push_back(std::move(load));
  }
}

/// The free nodes in order, and each node's index among them; refuses a body with none.
template <int dim> void number_free_nodes(const std::string& file, Problem<dim>& model) {
  const int n = static_cast<int>(model.constrained.size());
  model.free_index.assign(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i)
    if (!model.constrained[static_cast<std::size_t>(i)]) {
      model.free_index[static_cast<std::size_t>(i)] = static_cast<int>(model.free_nodes.size());
      model.free_nodes.push_back(i);
    }
  if (model.free_nodes.empty()) throw InputError(file + ": every node is constrained; nothing to simulate");
}

/// [initial]: a uniform velocity plus a spin about the centre of mass.
template <int dim>
void initial_velocity(const Scene& scene, const Mesh<dim>& mesh, const std::string& file, Problem<dim>& model) {
  const int n = mesh.num_nodes();
  model.initial_velocity = Nodal<dim>::Zero(dim, n);
  if (scene.initial_velocity.size() > 0)
    model.initial_velocity.colwise() = as_vec<dim>(scene.initial_velocity, "[initial].velocity", file);
  if (scene.initial_angular_velocity.size() > 0) {
    const int want = dim == 2 ? 1 : 3;
    if (scene.initial_angular_velocity.size() != want)
      throw InputError(file + ": [initial].angular_velocity must be " +
                       (dim == 2 ? "a number in 2D" : "a 3-vector in 3D"));
    const Vec<dim> centroid = centre_of_mass(mesh);
    for (int i = 0; i < n; ++i) {
      const Vec<dim> r = mesh.points.col(i) - centroid;
      if constexpr (dim == 2) {
        const double w = scene.initial_angular_velocity[0];
        model.initial_velocity.col(i) += Vec<dim>(-w * r.y(), w * r.x());
      } else {
        const Eigen::Vector3d w = scene.initial_angular_velocity;
        model.initial_velocity.col(i) += w.cross(r);
      }
    }
  }
}

/// Probes: a point probe snapped to its nearest node, at most the longest edge away; a load
/// probe on the named load's nodes, each weighted by its share of the load's force.
template <int dim>
void resolve_probes(const Scene& scene, const Mesh<dim>& mesh, double longest, const std::string& file,
                    Problem<dim>& model) {
  for (const auto& p : scene.probes) {
    const std::string what = "probe \"" + p.name + "\"";
    if (p.load.empty()) {
      const Vec<dim> x = as_vec<dim>(p.point, what + ".point", file);
      const int node = nearest_node(mesh, x);
      model.probes.push_back({p.name, node});
      model.probe_distance.push_back(snap_distance(mesh, longest, x, node, what, file));
      model.probe_weights.push_back({{node, 1.0}});
      continue;
    }
    const auto load =
        std::find_if(model.loads.begin(), model.loads.end(), [&](const Load<dim>& l) { return l.name == p.load; });
    if (load == model.loads.end())
      throw InputError(file + ": " + what + ".load: no [[load]] is named \"" + p.load + "\"");
    std::vector<std::pair<int, double>> weights;
    double total = 0;
    Vec<dim> centre = Vec<dim>::Zero();
    for (std::size_t k = 0; k < load->nodes.size(); ++k) {
      const double share = load->force.col(static_cast<Eigen::Index>(k)).norm();
      weights.push_back({load->nodes[k], share});
      total += share;
      centre += share * mesh.points.col(load->nodes[k]);
    }
    if (!(total > 0)) throw InputError(file + ": " + what + ".load: the load \"" + p.load + "\" has no force");
    centre /= total;
    int node = weights.front().first;
    for (auto& [n, w] : weights) {
      w /= total;
      if ((mesh.points.col(n) - centre).norm() < (mesh.points.col(node) - centre).norm()) node = n;
    }
    model.probes.push_back({p.name, node});
    model.probe_distance.push_back(0.0);
    model.probe_weights.push_back(std::move(weights));
  }
}

template <int dim> Problem<dim> build_problem(const Scene& scene, Mesh<dim> mesh) {
  const std::string file = scene.file.string();
  Problem<dim> model;
  model.duration = scene.duration;
  model.output_interval = scene.output_interval;
  const double longest = longest_edge(mesh);
  resolve_supports(scene, mesh, longest, file, model);
  resolve_loads(scene, mesh, longest, file, model);
  number_free_nodes(file, model);
  initial_velocity(scene, mesh, file, model);
  resolve_probes(scene, mesh, longest, file, model);
  model.mesh = std::move(mesh);
  return model;
}

template struct Problem<2>;
template struct Problem<3>;
template Problem<2> build_problem<2>(const Scene&, Mesh<2>);
template Problem<3> build_problem<3>(const Scene&, Mesh<3>);

} // namespace vtb
