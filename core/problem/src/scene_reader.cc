#include "scene_reader.hh"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace vtb {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), std::size_t{0});
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

namespace detail {

std::string positive(double v) {
  return v > 0 ? "" : "must be > 0";
}
std::string non_negative(double v) {
  return v >= 0 ? "" : "must be >= 0";
}

TableReader::TableReader(const toml::table& table, std::string path, std::string file,
                         std::initializer_list<std::string_view> allowed)
    : m_table(table), m_path(std::move(path)), m_file(std::move(file)) {
  for (auto&& [k, v] : table) {
    const std::string_view key = k.str();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string_view best;
    std::size_t best_d = 1000;
    for (std::string_view a : allowed) {
      const std::size_t d = edit_distance(key, a);
      if (d < best_d) {
        best_d = d;
        best = a;
      }
    }
    std::string msg = "unknown key";
    if (!best.empty() && best_d <= std::max<std::size_t>(3, key.size() / 2))
      msg += "; did you mean '" + std::string(best) + "'?";
    else {
      msg += "; known keys:";
      for (std::string_view a : allowed) msg += " " + std::string(a);
    }
    fail_node(&v, key, msg);
  }
}

std::string TableReader::where(const toml::node* n, std::string_view key) const {
  std::string s = m_file;
  if (n && n->source().begin.line > 0) s += ":" + std::to_string(n->source().begin.line);
  s += ": " + m_path;
  if (!key.empty()) s += (m_path.empty() ? "" : ".") + std::string(key);
  return s;
}

void TableReader::fail(std::string_view key, const std::string& what) const {
  fail_node(m_table.get(key), key, what);
}

void TableReader::fail_node(const toml::node* n, std::string_view key, const std::string& what) const {
  throw InputError(where(n ? n : &m_table, key) + ": " + what);
}

double TableReader::number(std::string_view key, std::optional<double> fallback,
                           const std::function<std::string(double)>& check) const {
  const toml::node* n = m_table.get(key);
  if (!n) {
    if (!fallback) fail(key, "missing (required)");
    return *fallback;
  }
  if (!n->is_number()) fail(key, "must be a number");
  // toml++ refuses integers that a double cannot hold exactly (beyond 2^53).
  const std::optional<double> x = n->value<double>();
  if (!x) fail(key, "must be a number a double can hold exactly");
  const double v = *x;
  if (!std::isfinite(v)) fail(key, "must be finite");
  if (check)
    if (const std::string e = check(v); !e.empty()) {
      std::ostringstream os;
      os << v;
      fail(key, "= " + os.str() + ": " + e);
    }
  return v;
}

int TableReader::integer(std::string_view key, std::optional<int> fallback, int min, int max) const {
  const toml::node* n = m_table.get(key);
  if (!n) {
    if (!fallback) fail(key, "missing (required)");
    return *fallback;
  }
  if (!n->is_integer()) fail(key, "must be an integer");
  const auto v = n->value<std::int64_t>().value();
  if (v < min || v > max)
    fail(key, "= " + std::to_string(v) + ": must be in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return static_cast<int>(v);
}

bool TableReader::boolean(std::string_view key, std::optional<bool> fallback) const {
  const toml::node* n = m_table.get(key);
  if (!n) {
    if (!fallback) fail(key, "missing (required)");
    return *fallback;
  }
  if (!n->is_boolean()) fail(key, "must be true or false");
  return n->value<bool>().value();
}

std::string TableReader::string(std::string_view key, std::optional<std::string> fallback,
                                const std::vector<std::string_view>& choices) const {
  const toml::node* n = m_table.get(key);
  std::string v;
  if (!n) {
    if (!fallback) fail(key, "missing (required)");
    v = *fallback;
  } else {
    if (!n->is_string()) fail(key, "must be a string");
    v = n->value<std::string>().value();
  }
  if (!choices.empty() && std::find(choices.begin(), choices.end(), v) == choices.end()) {
    std::string msg = "= \"" + v + "\": must be one of";
    for (auto c : choices) msg += " " + std::string(c);
    const auto nearest = std::min_element(choices.begin(), choices.end(),
                                          [&](auto a, auto b) { return edit_distance(v, a) < edit_distance(v, b); });
    if (edit_distance(v, *nearest) <= std::max<std::size_t>(3, v.size() / 2))
      msg += "; did you mean \"" + std::string(*nearest) + "\"?";
    fail(key, msg);
  }
  return v;
}

Eigen::VectorXd TableReader::vector(std::string_view key, std::size_t min_len, std::size_t max_len) const {
  const toml::node* n = m_table.get(key);
  if (!n) fail(key, "missing (required)");
  const toml::array* a = n->as_array();
  if (!a) fail(key, "must be an array of numbers");
  if (a->size() < min_len || a->size() > max_len)
    fail(key, "must have " +
                  (min_len == max_len ? std::to_string(min_len)
                                      : std::to_string(min_len) + " to " + std::to_string(max_len)) +
                  " entries, has " + std::to_string(a->size()));
  Eigen::VectorXd v(static_cast<Eigen::Index>(a->size()));
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& e = *a->get(i);
    const std::optional<double> x = e.is_number() ? e.value<double>() : std::nullopt;
    if (!x) fail(key, "entry " + std::to_string(i) + " must be a number a double can hold exactly");
    v[static_cast<Eigen::Index>(i)] = *x;
    if (!std::isfinite(v[static_cast<Eigen::Index>(i)])) fail(key, "entry " + std::to_string(i) + " must be finite");
  }
  return v;
}

const toml::table* TableReader::table(std::string_view key) const {
  const toml::node* n = m_table.get(key);
  if (!n) return nullptr;
  if (!n->is_table()) fail(key, "must be a table");
  return n->as_table();
}

std::vector<const toml::table*> TableReader::tables(std::string_view key) const {
  std::vector<const toml::table*> out;
  const toml::node* n = m_table.get(key);
  if (!n) return out;
  const toml::array* a = n->as_array();
  if (!a || !a->is_array_of_tables()) fail(key, "must be an array of tables ([[" + std::string(key) + "]])");
  for (const auto& e : *a) out.push_back(e.as_table());
  return out;
}

} // namespace detail
} // namespace vtb
