#include "vtb/harness/tex.hh"

#include <cctype>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace vtb::harness {

std::string tex_escape(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
    case '\\':
      out += "\\textbackslash{}";
      break;
    case '{':
      out += "\\{";
      break;
    case '}':
      out += "\\}";
      break;
    case '_':
      out += "\\_";
      break;
    case '%':
      out += "\\%";
      break;
    case '&':
      out += "\\&";
      break;
    case '#':
      out += "\\#";
      break;
    case '$':
      out += "\\$";
      break;
    case '~':
      out += "\\textasciitilde{}";
      break;
    case '^':
      out += "\\textasciicircum{}";
      break;
    default:
      if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) out += c;
    }
  }
  return out;
}

std::string tex_number(double value, int digits) {
  if (std::isnan(value)) return "n/a";
  if (std::isinf(value)) return value > 0 ? "\\ensuremath{\\infty}" : "\\ensuremath{-\\infty}";
  // Large values as whole numbers (30020, not 3e+04); small ones in scientific notation below.
  if (std::abs(value) >= std::pow(10.0, digits) && std::abs(value) < 1e9) return std::to_string(std::llround(value));
  std::ostringstream os;
  os << std::setprecision(digits) << value;
  std::string s = os.str();
  const auto e = s.find('e');
  if (e == std::string::npos) return s;
  // 1.5e-05 -> 1.5\times10^{-5}, in math mode wherever it lands.
  const int exponent = std::stoi(s.substr(e + 1));
  return "\\ensuremath{" + s.substr(0, e) + "\\times10^{" + std::to_string(exponent) + "}}";
}

std::string plain_number(double value) {
  std::ostringstream os;
  os << std::setprecision(8) << value;
  return os.str();
}

std::string tex_macro(const std::string& name, const std::string& value) {
  for (const char c : name)
    if (!std::isalpha(static_cast<unsigned char>(c))) throw std::logic_error("tex_macro: bad name " + name);
  return "\\newcommand\\" + name + "{" + value + "}\n";
}

} // namespace vtb::harness
