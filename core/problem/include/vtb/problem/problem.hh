#pragma once
/// \file
/// What a scene describes and every model discretises, resolved against the mesh: the mesh,
/// the supports and drives, the loads, the initial state, the probes and the sample times.
/// Built once from the scene; the spring network (model.hh) and the FEM (reference_fem) are
/// both made from it, and the FEM sees nothing else.

#include "vtb/linalg/nodal.hh"
#include "vtb/meshes/region.hh"
#include "vtb/problem/scene.hh"

#include <array>
#include <optional>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace vtb {

/// Switch-on profile of loads and drives: 0 before `start`, then a linear ramp to 1 over
/// `ramp` seconds (a step when ramp = 0).
inline double ramp_factor(double t, double start, double ramp) {
  if (t < start) return 0.0;
  if (ramp <= 0) return 1.0;
  return t >= start + ramp ? 1.0 : (t - start) / ramp;
}
/// Time derivative of ramp_factor (0 at the kinks).
inline double ramp_rate(double t, double start, double ramp) {
  return (ramp > 0 && t >= start && t < start + ramp) ? 1.0 / ramp : 0.0;
}

/// A fix (displacement 0) or drive (prescribed displacement), with its reaction reported.
template <int dim> struct Support {
  std::string name;
  std::vector<int> nodes;
  std::vector<std::array<int, dim>> facets; ///< boundary facets the region covers (for higher-order FEM)
  std::optional<Box<dim>> box;              ///< the region's box, if it was given by one
  bool driven = false;
  Vec<dim> displacement = Vec<dim>::Zero();
  double start = 0, ramp = 0;
};

/// A load: fixed nodal forces (lumped traction or point force) times the ramp.
template <int dim> struct Load {
  std::string name;
  std::vector<int> nodes;
  Nodal<dim> force; ///< column per entry of `nodes`
  /// A uniform traction: the facets and the total force (empty facets: a nodal load).
  std::vector<std::array<int, dim>> facets;
  Vec<dim> total = Vec<dim>::Zero();
  double start = 0, ramp = 0;
};

template <int dim> struct Problem {
  static constexpr int dimension = dim;
  Mesh<dim> mesh;
  std::vector<Support<dim>> supports;
  std::vector<Load<dim>> loads;
  std::vector<char> constrained; ///< per node: fixed or driven
  std::vector<int> free_nodes;   ///< sorted
  std::vector<int> free_index;   ///< node -> index in free_nodes, or -1
  Nodal<dim> initial_velocity;   ///< the scene's translation and spin (about the centre of mass)
  /// name, node: a point probe's node; a load probe's node nearest the load's centre (where a
  /// viewer marks it)
  std::vector<std::pair<std::string, int>> probes;
  std::vector<double> probe_distance; ///< per probe: from its scene point to its node, m (0 for a load probe)
  /// Per probe: the nodes whose displacements it averages and their weights (summing to 1): a
  /// point probe's node alone, a load probe's nodes by their share of the load (ProbeDesc).
  std::vector<std::vector<std::pair<int, double>>> probe_weights;
  double duration = 0, output_interval = 0;

  int num_nodes() const { return mesh.num_nodes(); }
  bool has_constraints() const { return free_nodes.size() != constrained.size(); }
  /// Probe p's displacement in the field u (dim x nodes; allocates nothing).
  template <class Field> Vec<dim> probe_displacement(std::size_t p, const Field& u) const {
    Vec<dim> x = Vec<dim>::Zero();
    for (const auto& [node, w] : probe_weights[p]) x += w * u.col(node);
    return x;
  }

  /// f = external load at time t (f is overwritten; allocates nothing).
  void external_forces(double t, Nodal<dim>& f) const;
  /// Sets displacement and velocity of every constrained node for time t.
  void apply_constraints(double t, Nodal<dim>& u, Nodal<dim>& v) const;
};

/// Resolves a scene against its mesh. Throws InputError naming the scene key when a vector
/// has the wrong dimension, a probe or point region lies farther from its nearest node than
/// the mesh's longest edge, a region selects no node, regions conflict (a node both fixed
/// and driven, or in two drives), or every node is constrained.
template <int dim> Problem<dim> build_problem(const Scene& scene, Mesh<dim> mesh);

/// Loads the scene's mesh (file or generator).
AnyMesh load_mesh(const Scene& scene);

/// Loads the scene's mesh and returns f(mesh) in the mesh's dimension; f takes a `Mesh<2>&`
/// and a `Mesh<3>&` (a generic lambda) and may move the mesh away.
template <class F> auto with_mesh(const Scene& scene, F&& f) {
  AnyMesh mesh = load_mesh(scene);
  return std::visit([&](auto& m) { return f(m); }, mesh);
}

/// Builds the problem in the mesh's dimension and returns f(problem); f takes a `Problem<2>&`
/// and a `Problem<3>&` (a generic lambda).
template <class F> auto with_problem(const Scene& scene, F&& f) {
  return with_mesh(scene, [&](auto& m) {
    constexpr int dim = std::decay_t<decltype(m)>::points_dim;
    Problem<dim> problem = build_problem<dim>(scene, std::move(m));
    return f(problem);
  });
}

} // namespace vtb
