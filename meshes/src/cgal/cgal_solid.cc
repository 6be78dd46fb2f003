// 3D tetrahedral solids with CGAL Mesh_3: a slab with protected sharp edges and a sphere.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh"

#include "mesh_3.hh"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace vtb {
namespace {

using namespace mesh_3;

/// A closed triangulated box surface with outward normals.
Polyhedron box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Polyhedron s;
  std::array<Polyhedron::Vertex_index, 8> v;
  for (int c = 0; c < 8; ++c)
    v[static_cast<std::size_t>(c)] =
        s.add_vertex(K::Point_3(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z()));
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  auto pt = [&](int c) {
    const auto& p = s.point(v[static_cast<std::size_t>(c)]);
    return Eigen::Vector3d(p.x(), p.y(), p.z());
  };
  auto tri = [&](int a, int b, int c) {
    const Eigen::Vector3d n = (pt(b) - pt(a)).cross(pt(c) - pt(a));
    if (n.dot(pt(a) - centre) > 0)
      s.add_face(v[static_cast<std::size_t>(a)], v[static_cast<std::size_t>(b)], v[static_cast<std::size_t>(c)]);
    else
      s.add_face(v[static_cast<std::size_t>(a)], v[static_cast<std::size_t>(c)], v[static_cast<std::size_t>(b)]);
  };
  // Each face of the cube: corners with one coordinate bit fixed, split along a diagonal.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      std::array<int, 4> q{};
      int n = 0;
      for (int c = 0; c < 8; ++c)
        if (((c >> axis) & 1) == side) q[static_cast<std::size_t>(n++)] = c;
      // q holds the corners in binary order: (0, 1, 3, 2) walks around the face.
      tri(q[0], q[1], q[3]);
      tri(q[0], q[3], q[2]);
    }
  return s;
}

Mesh3 mesh_slab(double size, const std::vector<Refinement>& refine,
                const Eigen::Vector3d& hi = Eigen::Vector3d(0.2, 0.05, 0.02)) {
  using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K, Polyhedron>;
  using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
  using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
  const Eigen::Vector3d lo(0, 0, 0);
  const Polyhedron s = box_surface(lo, hi);
  Domain domain(s);
  domain.detect_features();
  Mesh3 m = to_mesh(run_mesh_3<Domain, Tr, C3t3>(domain, size, refine));
  const double tol = 1e-9;
  const char* names[3][2] = {{"left", "right"}, {"bottom", "top"}, {"front", "back"}};
  for (int a = 0; a < 3; ++a) {
    add_group(m, names[a][0], [&](const Eigen::Vector3d& p) { return std::abs(p[a] - lo[a]) < tol; });
    add_group(m, names[a][1], [&](const Eigen::Vector3d& p) { return std::abs(p[a] - hi[a]) < tol; });
  }
  return m;
}

Mesh3 mesh_sphere(double size, const std::vector<Refinement>& refine) {
  using Domain = CGAL::Labeled_mesh_domain_3<K>;
  using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
  using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
  const double R = 0.05;
  auto f = [R](const K::Point_3& p) { return (p.x() * p.x() + p.y() * p.y() + p.z() * p.z()) / (R * R) - 1.0; };
  const Domain domain = Domain::create_implicit_mesh_domain(f, K::Sphere_3(CGAL::ORIGIN, 1.21 * R * R),
                                                            params::relative_error_bound = 1e-8);
  Mesh3 m = to_mesh(run_mesh_3<Domain, Tr, C3t3>(domain, size, refine));
  add_group(m, "surface", [](const Eigen::Vector3d&) { return true; });
  return m;
}

} // namespace

namespace {

void check_refinements(const std::string& what, const std::vector<Refinement>& refine) {
  for (std::size_t i = 0; i < refine.size(); ++i)
    if (const std::string why = refinement_error(refine[i]); !why.empty())
      throw InputError(what + ": refinement " + std::to_string(i) + ": " + why);
}

} // namespace

Mesh3 mesh_box(const Eigen::Vector3d& size, int nodes, const std::vector<Refinement>& refine) {
  if (!(size.array() > 0).all()) throw InputError("box: the size must be > 0");
  check_refinements("box", refine);
  return mesh_to_count("box", size.prod(), nodes, [&](double h) { return mesh_slab(h, refine, size); });
}

Mesh3 mesh_solid(const std::string& shape, int nodes, const std::vector<Refinement>& refine) {
  if (shape != "slab" && shape != "sphere") throw InputError("mesh_solid: shape must be slab or sphere, not " + shape);
  check_refinements(shape, refine);
  const double volume = shape == "slab" ? 0.2 * 0.05 * 0.02 : 4.0 / 3.0 * 3.14159265358979 * 0.05 * 0.05 * 0.05;
  return mesh_to_count(shape, volume, nodes,
                       [&](double h) { return shape == "slab" ? mesh_slab(h, refine) : mesh_sphere(h, refine); });
}

} // namespace vtb
