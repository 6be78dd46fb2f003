#pragma once
/// \file
/// Internal: typed, validated access to one TOML table with precise error messages.

#include "vtb/problem/scene.hh"

#include <toml++/toml.h>

#include <functional>
#include <initializer_list>
#include <vector>

namespace vtb {
/// Levenshtein distance: what "did you mean" suggestions rank by.
std::size_t edit_distance(std::string_view a, std::string_view b);
} // namespace vtb

namespace vtb::detail {

/// Reads the keys of one table. Construction refuses unknown keys, suggesting the nearest
/// known one; each getter checks type, finiteness and range and names FILE:LINE: [path].key.
class TableReader {
public:
  TableReader(const toml::table& table, std::string path, std::string file,
              std::initializer_list<std::string_view> allowed);

  bool has(std::string_view key) const { return m_table.contains(key); }
  const toml::node* node(std::string_view key) const { return m_table.get(key); }

  /// A real number; `check` returns "" when valid, else what is wrong ("must be > 0").
  double number(std::string_view key, std::optional<double> fallback,
                const std::function<std::string(double)>& check = {}) const;
  int integer(std::string_view key, std::optional<int> fallback, int min, int max) const;
  bool boolean(std::string_view key, std::optional<bool> fallback) const;
  /// A string, one of `choices` when given (else the nearest choice is suggested).
  std::string string(std::string_view key, std::optional<std::string> fallback,
                     const std::vector<std::string_view>& choices = {}) const;
  /// A vector of 1..max_len finite numbers (dimension is checked later against the mesh).
  Eigen::VectorXd vector(std::string_view key, std::size_t min_len, std::size_t max_len) const;
  /// A sub-table, or nullptr if absent; an error if present with another type.
  const toml::table* table(std::string_view key) const;
  /// An array of tables (`[[key]]`); empty if absent.
  std::vector<const toml::table*> tables(std::string_view key) const;

  /// Throws InputError "FILE:LINE: [path].key: what".
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;
  [[noreturn]] void fail_node(const toml::node* n, std::string_view key, const std::string& what) const;

  const std::string& path() const { return m_path; }
  const std::string& file() const { return m_file; }

private:
  std::string where(const toml::node* n, std::string_view key) const;
  const toml::table& m_table;
  std::string m_path;
  std::string m_file;
};

/// Range checks for TableReader::number.
std::string positive(double v);
std::string non_negative(double v);

} // namespace vtb::detail
