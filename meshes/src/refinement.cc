// The grading of a generated mesh toward where a scene acts (cgal_generate.hh, Refinement): no
// CGAL here, so that a scene and the CLI read and check refinements in any build.
#include "vtb/meshes/cgal_generate.hh"

#include <algorithm>
#include <cmath>

namespace vtb {

double graded_size(const Eigen::Vector3d& x, double body, const std::vector<Refinement>& refine) {
  double h = body;
  for (const Refinement& r : refine)
    h = std::min(h, r.size + r.growth * std::max(0.0, (x - r.center).norm() - r.radius));
  return h;
}

std::string refinement_error(const Refinement& r) {
  if (!r.center.allFinite()) return "center must be finite";
  if (!(r.radius >= 0) || !std::isfinite(r.radius)) return "radius must be >= 0";
  if (!(r.size > 0) || !std::isfinite(r.size)) return "size must be > 0";
  if (const std::string why = growth_error(r.growth); !why.empty()) return "growth " + why;
  return {};
}

std::string growth_error(double growth) {
  return (growth > 0 && growth <= 1) ? "" : "must be in (0, 1]";
}

} // namespace vtb
