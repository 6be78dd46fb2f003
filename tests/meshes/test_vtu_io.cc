// The VTU writer: compressed binary arrays decode (base64, then zlib, per VTK's layout) to the
// values written, fields of 2D vectors are padded to 3 components, and nothing half-written
// is left behind.
#include "support/fresh_dir.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/vtu_io.hh"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

namespace vtb {
namespace {

std::vector<unsigned char> unbase64(const std::string& s) {
  std::vector<unsigned char> out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue; // padding
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

/// The decoded bytes of a compressed binary DataArray body (header, then blocks).
std::vector<unsigned char> decode(const std::string& body) {
  // The header is base64 on its own: 3 + nblocks UInt32, i.e. a known number of characters.
  const std::vector<unsigned char> first = unbase64(body.substr(0, 8)); // 6 bytes: nblocks + part of next
  std::uint32_t blocks = 0;
  std::memcpy(&blocks, first.data(), 4);
  const std::size_t header_bytes = (3 + blocks) * 4, header_chars = (header_bytes + 2) / 3 * 4;
  const auto header = unbase64(body.substr(0, header_chars));
  std::vector<std::uint32_t> h(3 + blocks);
  std::memcpy(h.data(), header.data(), header_bytes);
  const auto data = unbase64(body.substr(header_chars));
  std::vector<unsigned char> out;
  std::size_t at = 0;
  for (std::uint32_t b = 0; b < blocks; ++b) {
    uLongf len = b + 1 == blocks ? h[2] : h[1];
    std::vector<unsigned char> block(len);
    EXPECT_EQ(uncompress(block.data(), &len, data.data() + at, h[3 + b]), Z_OK);
    out.insert(out.end(), block.begin(), block.begin() + static_cast<std::ptrdiff_t>(len));
    at += h[3 + b];
  }
  return out;
}

/// The body of the DataArray named `name` (or the first one after `after`).
std::string body_of(const std::string& xml, const std::string& marker) {
  const auto at = xml.find(marker);
  EXPECT_NE(at, std::string::npos) << marker;
  const auto start = xml.find('>', at) + 2, end = xml.find("\n</DataArray>", start);
  return xml.substr(start, end - start);
}

TEST(Vtu, CompressedBinaryArraysDecodeToTheValuesWritten) {
  const Mesh2 m = generate_rectangle({0.2, 0.05}, {40, 10});
  Eigen::Matrix<double, 2, Eigen::Dynamic> u(2, m.num_nodes());
  for (int i = 0; i < m.num_nodes(); ++i) u.col(i) << 1e-3 * std::sin(31.0 * i), -2e-4 * i;
  std::vector<double> cellv(static_cast<std::size_t>(m.num_cells()));
  for (std::size_t c = 0; c < cellv.size(); ++c) cellv[c] = 0.5 + 1e-3 * static_cast<double>(c);
  const test::FreshDir dir;
  write_vtu(m, dir / "a.vtu", {point_vectors<2>("displacement", u), VtuField{"strain", 1, true, cellv}});
  EXPECT_FALSE(std::filesystem::exists(dir / "a.vtu.part"));
  std::ifstream f(dir / "a.vtu");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string xml = ss.str();
  EXPECT_NE(xml.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
  // Displacement: padded to 3 components, Float32 (7 significant digits).
  const auto d = decode(body_of(xml, "Name=\"displacement\""));
  ASSERT_EQ(d.size(), static_cast<std::size_t>(m.num_nodes()) * 3 * sizeof(float));
  std::vector<float> dv(d.size() / sizeof(float));
  std::memcpy(dv.data(), d.data(), d.size());
  for (int i = 0; i < m.num_nodes(); ++i) {
    EXPECT_NEAR(dv[3 * static_cast<std::size_t>(i)], u(0, i), 1e-7 * std::abs(u(0, i)) + 1e-12);
    EXPECT_NEAR(dv[3 * static_cast<std::size_t>(i) + 1], u(1, i), 1e-7 * std::abs(u(1, i)) + 1e-12);
    EXPECT_EQ(dv[3 * static_cast<std::size_t>(i) + 2], 0.0f);
  }
  // A cell field, and the connectivity (Int32), which names every cell's vertices.
  const auto c = decode(body_of(xml, "Name=\"strain\""));
  ASSERT_EQ(c.size(), cellv.size() * sizeof(float));
  float last = 0;
  std::memcpy(&last, c.data() + c.size() - sizeof(float), sizeof(float));
  EXPECT_NEAR(last, cellv.back(), 1e-6);
  const auto conn = decode(body_of(xml, "Name=\"connectivity\""));
  ASSERT_EQ(conn.size(), static_cast<std::size_t>(m.num_cells()) * 3 * sizeof(std::int32_t));
  std::int32_t v0 = -1;
  std::memcpy(&v0, conn.data() + 3 * sizeof(std::int32_t), sizeof(std::int32_t));
  EXPECT_EQ(v0, m.cells[1][0]);
  // A wrongly sized field is refused before anything is written.
  EXPECT_THROW(write_vtu(m, dir / "b.vtu", {VtuField{"bad", 1, true, {1.0}}}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "b.vtu"));
  EXPECT_EQ(base64(reinterpret_cast<const unsigned char*>("Man"), 3), "TWFu");
  EXPECT_EQ(base64(reinterpret_cast<const unsigned char*>("Ma"), 2), "TWE=");
}

} // namespace
} // namespace vtb
