// A user's closed surface meshed into tetrahedra by CGAL Mesh_3, sharp edges protected, one
// group per surface patch.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"
#include "vtb/meshes/surface.hh"

#include "mesh_3.hh"

#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>

namespace vtb {
namespace {

using namespace mesh_3;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K, Polyhedron>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;

Polyhedron to_cgal(const Surface& in) {
  Polyhedron s;
  std::vector<Polyhedron::Vertex_index> v;
  v.reserve(in.points.size());
  for (const auto& p : in.points) v.push_back(s.add_vertex(K::Point_3(p.x(), p.y(), p.z())));
  for (const auto& t : in.triangles)
    s.add_face(v[static_cast<std::size_t>(t[0])], v[static_cast<std::size_t>(t[1])], v[static_cast<std::size_t>(t[2])]);
  return s;
}

/// The mesh with "surface" and one "patch_K" group per patch of the complex's boundary facets.
Mesh3 with_patches(const C3t3& c3t3) {
  std::map<Tr::Vertex_handle, int> node;
  Mesh3 m = to_mesh(c3t3, &node);
  std::map<std::array<int, 3>, int> patch;
  for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
    std::array<int, 3> ids{};
    for (int k = 0, j = 0; k < 4; ++k) {
      if (k == f->second) continue;
      const auto it = node.find(f->first->vertex(k));
      ids[static_cast<std::size_t>(j++)] = it == node.end() ? -1 : it->second;
    }
    std::sort(ids.begin(), ids.end());
    patch[ids] = static_cast<int>(c3t3.surface_patch_index(*f));
  }
  std::map<std::string, MeshGroup<3>> groups;
  for (const auto& facet : boundary_facets(m)) {
    std::array<int, 3> ids{facet[0], facet[1], facet[2]};
    std::sort(ids.begin(), ids.end());
    const auto it = patch.find(ids);
    for (const std::string& name :
         {std::string("surface"), "patch_" + std::to_string(it == patch.end() ? 0 : it->second)}) {
      auto& g = groups[name];
      g.facets.push_back(facet);
      g.nodes.insert(g.nodes.end(), facet.begin(), facet.end());
    }
  }
  for (auto& [name, g] : groups) {
    std::sort(g.nodes.begin(), g.nodes.end());
    g.nodes.erase(std::unique(g.nodes.begin(), g.nodes.end()), g.nodes.end());
    m.groups[name] = std::move(g);
  }
  return m;
}

} // namespace

Mesh3 mesh_surface(const Surface& surface, int nodes, double size, const std::vector<Refinement>& refine,
                   const std::string& name) {
  for (std::size_t i = 0; i < refine.size(); ++i)
    if (const std::string why = refinement_error(refine[i]); !why.empty())
      throw InputError(name + ": refinement " + std::to_string(i) + ": " + why);
  if ((nodes > 0) == (size > 0)) throw InputError(name + ": give a node count or an element size (one of them)");
  const Polyhedron s = to_cgal(surface);
  const double volume = CGAL::to_double(CGAL::Polygon_mesh_processing::volume(s));
  if (!(volume > 0)) throw InputError(name + ": the surface encloses no volume");
  auto make = [&](double h) {
    Domain domain(s);
    domain.detect_features(kFeatureAngle);
    return with_patches(run_mesh_3<Domain, Tr, C3t3>(domain, h, refine));
  };
  if (nodes > 0) return mesh_to_count(name, volume, nodes, make);
  if (!std::isfinite(size)) throw InputError(name + ": the element size must be finite");
  // A size that would give more than the node-count rule's ceiling is refused before meshing.
  if (volume * std::sqrt(2.0) / (size * size * size) * 4.1 > 500'000)
    throw InputError(name + ": element size " + std::to_string(size) + " m would give more than 500000 nodes");
  Mesh3 m = make(size);
  m.source = "CGAL " + name + " (" + std::to_string(m.num_nodes()) + " nodes)";
  return m;
}

} // namespace vtb
