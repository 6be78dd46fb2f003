#pragma once
/// \file
/// Unstructured meshes from CGAL: the paper's polygonal plate (2D constrained Delaunay
/// refinement + smoothing, exact node count) and 3D tetrahedral solids (Mesh_3).

#include "vtb/meshes/mesh.hh"

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace vtb {

/// A hole in a polygon: a convex polygon strictly inside it (its vertex mean is inside the
/// hole, which the mesher uses as the seed that keeps it empty); its edges form one group.
struct Hole {
  std::vector<Eigen::Vector2d> vertices;
  std::string group;
};

/// A simple polygon (counter-clockwise) with named boundary edges: edge k runs from vertex
/// k to vertex k + 1 (mod n); optionally with holes.
struct Polygon {
  std::vector<Eigen::Vector2d> vertices;
  std::map<std::string, std::vector<int>> edge_groups;
  std::vector<Hole> holes;
};

/// The plate of the paper's Fig. 3 as vtb models it: a thin hexagonal plate 0.2 m x 0.05 m
/// whose right end is chamfered (x from 0.15 to 0.2); group "clamp" is the left edge x = 0,
/// group "load" the right edge x = 0.2 (where the horizontal step force acts).
Polygon paper_plate();

/// Meshes a polygon with exactly `nodes` nodes and every angle >= min_angle_deg (<= 20.7,
/// the bound Delaunay refinement guarantees): refinement with a size bound chosen by a
/// deterministic scan, the missing nodes inserted at the centroids of the largest
/// triangles, then a smart Laplacian smoothing of interior nodes (a move is kept only if it
/// raises the smallest angle around the node). CGAL's own Lloyd optimiser is not used: it
/// visits vertices in memory-address order, so its output changes in the last digits from
/// one build to the next, and the canonical meshes must regenerate bit for bit.
/// Throws InputError if no mesh with that count and quality is found. Deterministic.
Mesh2 mesh_polygon(const Polygon& polygon, int nodes, double min_angle_deg = 20.0);

/// The largest hole mesh_rectangle cuts, as a fraction of the rectangle's shorter side: a
/// ligament of at least a tenth of that side on each side of the hole.
inline constexpr double kMaxHoleRadius = 0.4;

/// Why a hole of this radius does not fit a rectangle whose shorter side is `shorter` (one
/// phrase), or empty if it does.
inline std::string hole_error(double radius, double shorter) {
  if (radius <= kMaxHoleRadius * shorter) return {};
  std::ostringstream os;
  os << "hole radius " << radius << " m leaves less than a tenth of the shorter side (" << shorter
     << " m) on each side: at most " << kMaxHoleRadius * shorter << " m";
  return os.str();
}

/// An unstructured rectangle [0, size]: mesh_polygon of its four corners, exactly `nodes`
/// nodes; groups bottom, right, top, left (as the structured generator names them). With
/// hole_radius > 0, a circular hole of that radius at the centre (a polygon with edges about
/// as long as the mesh's, at least 16), its boundary the group "hole"; a radius above
/// kMaxHoleRadius x the shorter side is an InputError.
Mesh2 mesh_rectangle(const Eigen::Vector2d& size, int nodes, double hole_radius = 0);

/// How fast a refinement's size grows with distance beyond its radius (dimensionless), by
/// default: a neighbour's size differs from a cell's by at most about 25 % of the cell. At 0.4
/// the continuum itself on a held-out dome moved 5.5 % under the load (P2 on each mesh); at 0.25
/// every held-out body's answers under the load stay within 5 % of the uniform mesh's, the
/// large ones' on a quarter of its nodes or fewer (docs/meshes.md, the measured table).
inline constexpr double kRefineGrowth = 0.25;

/// Grading toward where a scene acts: the element size is `size` within `radius` of `center`
/// and grows with distance beyond it at `growth` (m of size per m of distance) until it
/// reaches the body's size. Several refinements take the smallest size at each point.
struct Refinement {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0;             ///< m, >= 0
  double size = 0;               ///< m, > 0
  double growth = kRefineGrowth; ///< in (0, 1]: slower grading costs nodes and moves the answers less (docs/meshes.md)
};

/// The element size at a point: `body` away from every refinement, graded toward each.
double graded_size(const Eigen::Vector3d& x, double body, const std::vector<Refinement>& refine);

/// Why a refinement is not usable (one phrase), or empty.
std::string refinement_error(const Refinement& r);

/// Why a growth is not usable ("must be in (0, 1]"), or empty: refinement_error's and the
/// scene reader's one check.
std::string growth_error(double growth);

/// An unstructured box [0, size] meshed by CGAL Mesh_3 to about `nodes` nodes (within 15 %),
/// sharp edges protected; groups left/right/bottom/top/front/back. Deterministic. With
/// refinements the body's size is what the node count sets, the refinements' sizes are kept.
Mesh3 mesh_box(const Eigen::Vector3d& size, int nodes, const std::vector<Refinement>& refine = {});

/// 3D solids meshed by CGAL Mesh_3 to about `nodes` nodes (within 15 %): shape "slab"
/// (0.2 x 0.05 x 0.02 box, sharp edges protected; groups left/right/bottom/top/front/back)
/// or "sphere" (radius 0.05 at the origin; group "surface"). Cells have radius-edge ratio
/// <= 2 and slivers are exuded (target dihedral >= 10 degrees). Deterministic.
Mesh3 mesh_solid(const std::string& shape, int nodes, const std::vector<Refinement>& refine = {});

struct Surface;

/// The angle (degrees) between two faces' normals beyond which their common edge is a sharp
/// feature that the mesh keeps (CGAL's detect_features).
inline constexpr double kFeatureAngle = 60.0;

/// The inside of a checked closed surface (surface.hh) meshed by CGAL Mesh_3 with the slab's
/// criteria, sharp edges (kFeatureAngle) protected: to about `nodes` nodes (within 15 %) when
/// nodes > 0, else at element size `size` (m). Groups: "surface" (every boundary facet) and
/// "patch_K" for each patch that the sharp edges bound (K from 1). Deterministic.
Mesh3 mesh_surface(const Surface& surface, int nodes, double size, const std::vector<Refinement>& refine = {},
                   const std::string& name = "surface");

} // namespace vtb
