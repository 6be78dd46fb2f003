#include "vtb/meshes/vtu_io.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>

namespace vtb {

std::string base64(const unsigned char* d, std::size_t n) {
  static constexpr char k[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const std::uint32_t b = (std::uint32_t{d[i]} << 16) | (i + 1 < n ? std::uint32_t{d[i + 1]} << 8 : 0u) |
                            (i + 2 < n ? std::uint32_t{d[i + 2]} : 0u);
    out += k[(b >> 18) & 63];
    out += k[(b >> 12) & 63];
    out += i + 1 < n ? k[(b >> 6) & 63] : '=';
    out += i + 2 < n ? k[b & 63] : '=';
  }
  return out;
}

namespace {

/// One DataArray body in VTK's compressed binary layout: a header of UInt32 words
/// [blocks, block size, last block size, compressed size of each block] base64-encoded on its
/// own, then the compressed blocks base64-encoded together.
std::string compressed(const void* data, std::size_t bytes) {
  constexpr std::size_t kBlock = 1 << 15;
  const auto* p = static_cast<const unsigned char*>(data);
  const std::size_t blocks = bytes == 0 ? 0 : (bytes + kBlock - 1) / kBlock;
  std::vector<std::uint32_t> header{static_cast<std::uint32_t>(blocks), static_cast<std::uint32_t>(kBlock),
                                    static_cast<std::uint32_t>(bytes == 0 ? 0 : bytes - (blocks - 1) * kBlock)};
  std::vector<unsigned char> body;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t len = std::min(kBlock, bytes - b * kBlock);
    uLongf out = compressBound(static_cast<uLong>(len));
    const std::size_t at = body.size();
    body.resize(at + out);
    if (compress2(body.data() + at, &out, p + b * kBlock, static_cast<uLong>(len), Z_DEFAULT_COMPRESSION) != Z_OK)
      throw std::runtime_error("vtu: zlib compression failed");
    body.resize(at + out);
    header.push_back(static_cast<std::uint32_t>(out));
  }
  return base64(reinterpret_cast<const unsigned char*>(header.data()), header.size() * sizeof(std::uint32_t)) +
         base64(body.data(), body.size());
}

template <class T>
void array(std::ostream& f, const char* type, const std::string& name, int components, const std::vector<T>& v) {
  f << "<DataArray type=\"" << type << "\"";
  if (!name.empty()) f << " Name=\"" << name << "\"";
  f << " NumberOfComponents=\"" << components << "\" format=\"binary\">\n"
    << compressed(v.data(), v.size() * sizeof(T)) << "\n</DataArray>\n";
}

/// Values with 2 components are padded to 3 (a 2D vector ParaView can glyph).
std::vector<double> padded(const VtuField& field, int& components) {
  components = field.components == 2 ? 3 : field.components;
  if (field.components != 2) return field.values;
  std::vector<double> out;
  for (std::size_t i = 0; i + 1 < field.values.size(); i += 2)
    out.insert(out.end(), {field.values[i], field.values[i + 1], 0.0});
  return out;
}

} // namespace

template <int dim>
VtuField point_vectors(const std::string& name, const Eigen::Matrix<double, dim, Eigen::Dynamic>& v) {
  return VtuField{name, dim, false, std::vector<double>(v.data(), v.data() + v.size())};
}

template <int dim>
void write_vtu(const Mesh<dim>& mesh, const std::filesystem::path& file, const std::vector<VtuField>& fields) {
  for (const auto& fl : fields) {
    const std::size_t n = static_cast<std::size_t>(fl.per_cell ? mesh.num_cells() : mesh.num_nodes());
    if (fl.values.size() != n * static_cast<std::size_t>(fl.components))
      throw std::invalid_argument("write_vtu: field " + fl.name + " has the wrong size");
  }
  write_file_atomically(file, [&](std::ostream& f) {
    f << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\""
      << mesh.num_nodes() << "\" NumberOfCells=\"" << mesh.num_cells() << "\">\n<Points>\n";
    // Float32 throughout: 7 significant digits are what a picture needs, and the files are
    // half the size (results at full precision are in probes.csv and reactions.csv).
    std::vector<float> xyz;
    xyz.reserve(static_cast<std::size_t>(mesh.num_nodes()) * 3);
    for (int i = 0; i < mesh.num_nodes(); ++i)
      xyz.insert(xyz.end(), {static_cast<float>(mesh.points(0, i)), static_cast<float>(mesh.points(1, i)),
                             dim == 3 ? static_cast<float>(mesh.points(dim - 1, i)) : 0.0f});
    array(f, "Float32", "", 3, xyz);
    f << "</Points>\n<Cells>\n";
    std::vector<std::int32_t> conn, offsets;
    std::vector<std::uint8_t> types(static_cast<std::size_t>(mesh.num_cells()), dim == 2 ? 5 : 10); // triangle, tetra
    for (const auto& c : mesh.cells) {
      for (int v : c) conn.push_back(v);
      offsets.push_back(static_cast<std::int32_t>(conn.size()));
    }
    array(f, "Int32", "connectivity", 1, conn);
    array(f, "Int32", "offsets", 1, offsets);
    array(f, "UInt8", "types", 1, types);
    f << "</Cells>\n";
    for (const bool cell : {false, true}) {
      f << (cell ? "<CellData>\n" : "<PointData>\n");
      for (const auto& fl : fields)
        if (fl.per_cell == cell) {
          int comps = 0;
          const std::vector<double> v = padded(fl, comps);
          array(f, "Float32", fl.name, comps, std::vector<float>(v.begin(), v.end()));
        }
      f << (cell ? "</CellData>\n" : "</PointData>\n");
    }
    f << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  });
}

template void write_vtu<2>(const Mesh<2>&, const std::filesystem::path&, const std::vector<VtuField>&);
template void write_vtu<3>(const Mesh<3>&, const std::filesystem::path&, const std::vector<VtuField>&);
template VtuField point_vectors<2>(const std::string&, const Eigen::Matrix<double, 2, Eigen::Dynamic>&);
template VtuField point_vectors<3>(const std::string&, const Eigen::Matrix<double, 3, Eigen::Dynamic>&);

} // namespace vtb
