#include "vtb/meshes/msh_io.hh"

#include "vtb/base/atomic_file.hh"

#include "vtb/base/input_error.hh"
#include "vtb/base/module.hh"
#include "vtb/meshes/isolated.hh"
#include "vtb/meshes/mesh_serialize.hh"
#include "vtb/meshes/msh_prescan.hh"

#include "gmsh_backend.hh"

#include <algorithm>
#include <chrono>
#include <iostream>

namespace vtb {
namespace {

/// The gmsh module (gmsh_backend.hh), loaded by the reader's child or for a write.
class GmshModule {
public:
  GmshModule() : m_module("vtb_gmsh_backend.so", VTB_GMSH_BACKEND, "vtb's gmsh module") {}
  template <class Fn> Fn* function(const char* name) const {
    auto* f = reinterpret_cast<Fn*>(m_module.symbol(name));
    if (f == nullptr) throw IoError(std::string("vtb's gmsh module (vtb_gmsh_backend.so) has no ") + name);
    return f;
  }

private:
  Module m_module;
};

/// The reader's work in the isolated child (isolated.hh): "M" + the serialized mesh, or "E" +
/// the backend's error.
std::string read_in_child(const std::string& src) {
  std::string out;
  try {
    GmshModule().function<gmsh_backend::ReadFn>(gmsh_backend::kRead)(src.c_str(), &out);
  } catch (const std::exception& e) {
    out = std::string("E") + e.what();
  }
  return out;
}

AnyMesh read_msh_isolated(const std::string& src, std::chrono::seconds limit) {
  const std::string data = run_isolated(src, "mesh", limit, [&] { return read_in_child(src); });
  if (data.empty()) throw InputError(src + ": the mesh reader failed on this file");
  if (data[0] == 'E') throw InputError(data.substr(1));
  return deserialize(std::string_view(data).substr(1), src);
}

} // namespace

AnyMesh read_msh(const std::filesystem::path& file) {
  const std::string src = file.string();
  const std::string content = read_untrusted(file, "mesh");
  prescan_msh(content, src);
  AnyMesh mesh = read_msh_isolated(src, std::chrono::seconds(8));
  const int flipped = std::visit([](auto& m) { return check_and_orient(m); }, mesh);
  if (flipped > 0) std::cerr << "vtb: warning: " << src << ": " << flipped << " inverted cells re-oriented\n";
  return mesh;
}

template <int dim> void write_msh(const Mesh<dim>& mesh, const std::filesystem::path& file) {
  // gmsh picks the format from the extension, so the temporary name ends in .msh too.
  const std::filesystem::path tmp = file.parent_path() / ("." + file.filename().string() + ".part.msh");
  ensure_directory(file.parent_path());
  std::string error;
  try {
    const GmshModule gmsh;
    gmsh.function<gmsh_backend::WriteFn<dim>>(gmsh_backend::kWrite<dim>)(&mesh, tmp.c_str(), &error);
  } catch (const IoError& e) {
    error = e.what();
  }
  if (!error.empty()) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw IoError(file.string() + ": cannot write: " + error);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError(file.string() + ": cannot write: " + ec.message());
  }
}

template void write_msh<2>(const Mesh<2>&, const std::filesystem::path&);
template void write_msh<3>(const Mesh<3>&, const std::filesystem::path&);

} // namespace vtb
