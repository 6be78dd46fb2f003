#include "vtb/problem/support_notes.hh"

#include <cmath>

namespace vtb {
namespace {

/// Mostly along z: |z| larger than x's and y's (a 3-vector only).
bool along_z(const Eigen::VectorXd& v) {
  return v.size() == 3 && std::abs(v[2]) > std::abs(v[0]) && std::abs(v[2]) > std::abs(v[1]);
}

bool three_d(const Scene& s) {
  if (s.mesh.generated() && s.mesh.size.size() == 3) return true;
  for (const auto& l : s.loads)
    if (l.total_force.size() == 3) return true;
  for (const auto& d : s.drives)
    if (d.displacement.size() == 3) return true;
  for (const auto& p : s.probes)
    if (p.point.size() == 3) return true;
  return s.haptics && s.haptics->plane.has_value();
}

/// What acts along z, named for the note ("load \"press\"", "the device"), or empty.
std::string acting_along_z(const Scene& s) {
  for (const auto& l : s.loads)
    if (along_z(l.total_force)) return "[[load]] " + l.region.label;
  for (const auto& d : s.drives)
    if (along_z(d.displacement)) return "[[drive]] " + d.region.label;
  if (s.haptics && s.haptics->plane) {
    const auto& p = *s.haptics->plane;
    if (along_z(p.x_axis) || along_z(p.y_axis)) return "the device (its [haptics.plane] holds z)";
  }
  return "";
}

std::string note_for(const std::string& kind, const std::string& label, const std::string& group,
                     const std::string& what) {
  const bool bottom = group == "bottom";
  return kind + " " + label + " names group \"" + group + "\", which in 3D is the face at the " +
         (bottom ? "smallest" : "largest") + " y (" + (bottom ? "y_min" : "y_max") + "), while " + what +
         " acts along z: the face at the " + (bottom ? "smallest" : "largest") + " z is group = \"" +
         (bottom ? "z_min" : "z_max") + "\" (write \"" + (bottom ? "y_min" : "y_max") +
         "\" to keep the y face without this note; docs/scenes.md)";
}

} // namespace

std::vector<std::string> support_face_notes(const Scene& scene) {
  std::vector<std::string> notes;
  if (!three_d(scene)) return notes;
  const std::string what = acting_along_z(scene);
  if (what.empty()) return notes;
  const auto check = [&](const char* kind, const RegionDesc& r) {
    if (r.group == "bottom" || r.group == "top") notes.push_back(note_for(kind, r.label, r.group, what));
  };
  for (const auto& f : scene.fixes) check("[[fix]]", f.region);
  for (const auto& d : scene.drives) check("[[drive]]", d.region);
  return notes;
}

} // namespace vtb
