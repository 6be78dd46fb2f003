#include "vtb/meshes/msh_prescan.hh"

#include "vtb/base/input_error.hh"

#include <charconv>
#include <vector>

namespace vtb {
namespace {

/// Parses the whitespace-separated unsigned integers of one line; false on anything else.
bool parse_counts(std::string_view line, std::vector<unsigned long long>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    if (i == line.size()) break;
    unsigned long long v = 0;
    const auto [ptr, ec] = std::from_chars(line.data() + i, line.data() + line.size(), v);
    if (ec != std::errc() || ptr == line.data() + i) return false;
    out.push_back(v);
    i = static_cast<std::size_t>(ptr - line.data());
  }
  return true;
}

/// The line that follows position `pos` (after its newline), and advances pos past it.
std::string_view next_line(std::string_view s, std::size_t& pos) {
  const std::size_t end = s.find('\n', pos);
  const std::string_view line = s.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos);
  pos = end == std::string_view::npos ? s.size() : end + 1;
  return line;
}

} // namespace

void prescan_msh(std::string_view s, const std::string& src) {
  const auto size = static_cast<unsigned long long>(s.size());
  std::size_t pos = 0;
  // Skip blank lines, then the header must open the file.
  std::string_view first;
  while (pos < s.size() && (first = next_line(s, pos)).find_first_not_of(" \t\r") == std::string_view::npos) {
  }
  if (first.substr(0, 11) != "$MeshFormat") throw InputError(src + ": not a Gmsh .msh file (no $MeshFormat header)");
  const std::string_view fmt = next_line(s, pos);
  const std::size_t sp = fmt.find(' ');
  const std::string_view version = fmt.substr(0, sp);
  const bool v4 = version == "4.1" || version == "4" || version == "4.0";
  if (!v4 && version != "2.2" && version != "2")
    throw InputError(src + ": unsupported .msh version \"" + std::string(version) + "\" (vtb reads 2.2 and 4.x)");

  std::vector<unsigned long long> c;
  auto fits = [&](unsigned long long count, unsigned long long min_bytes, const char* what) {
    if (count > size / min_bytes)
      throw InputError(src + ": " + what + " declares " + std::to_string(count) + " entries, more than a " +
                       std::to_string(size) + "-byte file can hold");
  };
  for (const char* section : {"$Nodes", "$Elements"}) {
    const std::string key = std::string("\n") + section;
    std::size_t at = s.find(key + "\n");
    if (at == std::string_view::npos) at = s.find(key + "\r\n");
    if (at == std::string_view::npos) throw InputError(src + ": missing " + section + " section");
    std::size_t p = at + 1;
    next_line(s, p);
    const std::string_view header = next_line(s, p);
    if (!parse_counts(header, c) || c.empty() || (v4 && c.size() != 4) || (!v4 && c.size() != 1))
      throw InputError(src + ": " + section + ": malformed header line \"" + std::string(header.substr(0, 60)) + "\"");
    const bool nodes = std::string_view(section) == "$Nodes";
    if (v4) {
      // numEntityBlocks numX minTag maxTag.
      fits(c[0], 8, (std::string(section) + " entity blocks").c_str());
      fits(c[1], nodes ? 8 : 4, section);
      if (c[1] > 0 && (c[2] > c[3] || c[3] - c[2] > 10 * c[1] + 1'000'000))
        throw InputError(src + ": " + section + ": tag range [" + std::to_string(c[2]) + ", " + std::to_string(c[3]) +
                         "] is far sparser than its " + std::to_string(c[1]) + " entries");
    } else {
      fits(c[0], nodes ? 8 : 6, section);
    }
  }
}

} // namespace vtb
