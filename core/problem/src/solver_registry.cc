#include "vtb/problem/solver_registry.hh"

#include "scene_reader.hh"
#include "vtb/base/input_error.hh"

namespace vtb::solvers {

const Entry& find(std::string_view name, std::string_view where) {
  for (const Entry& e : kEntries)
    if (name == e.name) return e;
  std::string_view best;
  std::size_t best_d = 1000;
  for (const Entry& e : kEntries)
    if (const std::size_t d = edit_distance(name, e.name); d < best_d) {
      best_d = d;
      best = e.name;
    }
  std::string msg = std::string(where) + ": unknown solver \"" + std::string(name) + "\"";
  if (best_d <= std::max<std::size_t>(3, name.size() / 2)) msg += "; did you mean \"" + std::string(best) + "\"?";
  throw InputError(msg + " (known: " + list() + ")");
}

void select(std::string_view name, std::string_view where, std::string& kind, std::string& filter) {
  const Entry& e = find(name, where);
  kind = e.kind;
  if (*e.filter) filter = e.filter;
}

std::vector<std::string> names(bool (*keep)(const Entry&)) {
  std::vector<std::string> v;
  for (const Entry& e : kEntries)
    if (!keep || keep(e)) v.emplace_back(e.name);
  return v;
}

std::string list(bool (*keep)(const Entry&)) {
  const auto v = names(keep);
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i == 0 ? "" : i + 1 == v.size() ? " or " : ", ") + v[i];
  return s;
}

} // namespace vtb::solvers
