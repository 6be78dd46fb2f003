#include "vtb/harness/csv_table.hh"

#include "vtb/base/input_error.hh"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace vtb::harness {
namespace {

/// Splits one record; `quoted` fields may hold commas and doubled quotes (no newlines: vtb
/// never writes them).
std::vector<std::string> split_record(const std::string& line, const std::string& where) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  if (quoted) throw InputError(where + ": unterminated quoted field");
  return fields;
}

} // namespace

CsvTable CsvTable::read(const std::filesystem::path& file) {
  std::ifstream f(file);
  if (!f) throw InputError(file.string() + ": cannot read (missing from the reproduction?)");
  std::ostringstream os;
  os << f.rdbuf();
  return parse(os.str(), file.string());
}

CsvTable CsvTable::parse(const std::string& text, const std::string& name) {
  CsvTable t;
  t.m_name = name;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    auto fields = split_record(line, name + ":" + std::to_string(number));
    if (t.m_header.empty()) {
      t.m_header = std::move(fields);
      continue;
    }
    if (fields.size() != t.m_header.size())
      throw InputError(name + ":" + std::to_string(number) + ": " + std::to_string(fields.size()) +
                       " fields where the header has " + std::to_string(t.m_header.size()));
    t.m_rows.push_back(std::move(fields));
  }
  if (t.m_header.empty()) throw InputError(name + ": empty (no header row)");
  return t;
}

bool CsvTable::has_column(const std::string& column) const {
  return std::find(m_header.begin(), m_header.end(), column) != m_header.end();
}

std::size_t CsvTable::index(const std::string& column) const {
  const auto it = std::find(m_header.begin(), m_header.end(), column);
  if (it == m_header.end()) throw InputError(m_name + ": no column \"" + column + "\"");
  return static_cast<std::size_t>(it - m_header.begin());
}

const std::string& CsvTable::text(std::size_t row, const std::string& column) const {
  return m_rows.at(row)[index(column)];
}

double CsvTable::number(std::size_t row, const std::string& column) const {
  const std::string& s = text(row, column);
  if (s.empty() || s == "nan" || s == "n/a" || s == "-nan") return std::nan("");
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size())
    throw InputError(m_name + ": row " + std::to_string(row + 2) + ", column \"" + column + "\": \"" + s +
                     "\" is not a number");
  return v;
}

} // namespace vtb::harness
