#pragma once
/// \file
/// A CSV file as vtb writes it (RFC 4180: a header row, fields quoted when they hold commas or
/// quotes), read back by name: what the paper's data step reads from a reproduction.

#include <filesystem>
#include <string>
#include <vector>

namespace vtb::harness {

class CsvTable {
public:
  /// Reads `file`; InputError naming the file and line when it is missing, has no header, or a
  /// row's field count differs from the header's.
  static CsvTable read(const std::filesystem::path& file);
  /// From text (tests); `name` stands for the file in messages.
  static CsvTable parse(const std::string& text, const std::string& name);

  std::size_t rows() const { return m_rows.size(); }
  /// The field of `row` in column `column`; InputError naming the file and column if absent.
  const std::string& text(std::size_t row, const std::string& column) const;
  /// The same as a number ("nan", "n/a" and "" are NaN); InputError if it is not one.
  double number(std::size_t row, const std::string& column) const;
  bool has_column(const std::string& column) const;

private:
  std::size_t index(const std::string& column) const;
  std::string m_name;
  std::vector<std::string> m_header;
  std::vector<std::vector<std::string>> m_rows;
};

} // namespace vtb::harness
