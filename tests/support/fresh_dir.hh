#pragma once
/// A fresh, empty folder of its own for each test (and each call), removed when the guard
/// goes out of scope: no test reads what an earlier run or a parallel test left behind.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace vtb::test {

class FreshDir {
public:
  /// Makes <tmp>/vtb_<suite>_<test>_XXXXXX with mkdtemp (unique across processes and calls).
  FreshDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "vtb";
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    std::string templ = (std::filesystem::temp_directory_path() / ("vtb_" + name + "_XXXXXX")).string();
    if (!mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed for " + templ);
    m_path = templ;
  }
  ~FreshDir() {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
  }
  FreshDir(const FreshDir&) = delete;
  FreshDir& operator=(const FreshDir&) = delete;

  const std::filesystem::path& path() const { return m_path; }
  std::filesystem::path operator/(const std::string& leaf) const { return m_path / leaf; }

private:
  std::filesystem::path m_path;
};

/// The whole text of a file ("" if it cannot be read).
inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

} // namespace vtb::test
