#include "vtb/meshes/mesh_serialize.hh"

#include "vtb/base/input_error.hh"

#include <cstring>

namespace vtb {
namespace {

class Writer {
public:
  template <typename T> void put(const T& v) { m_out.append(reinterpret_cast<const char*>(&v), sizeof(T)); }
  void put_bytes(const void* p, std::size_t n) {
    if (n > 0) m_out.append(static_cast<const char*>(p), n);
  }
  std::string take() { return std::move(m_out); }

private:
  std::string m_out;
};

class Reader {
public:
  Reader(std::string_view in, const std::string& src) : m_in(in), m_src(src) {}
  template <typename T> T get() {
    T v;
    get_bytes(&v, sizeof(T));
    return v;
  }
  void get_bytes(void* p, std::size_t n) {
    if (n > m_in.size() - m_pos) throw InputError(m_src + ": truncated mesh data from the reader");
    if (n == 0) return; // p may be the null data() of an empty vector: memcpy must not see it
    std::memcpy(p, m_in.data() + m_pos, n);
    m_pos += n;
  }
  std::size_t count(std::size_t item) {
    const auto n = get<std::uint64_t>();
    if (n > (m_in.size() - m_pos) / item) throw InputError(m_src + ": corrupt mesh data from the reader");
    return static_cast<std::size_t>(n);
  }

private:
  std::string_view m_in;
  std::size_t m_pos = 0;
  const std::string& m_src;
};

template <int dim> void write_mesh(Writer& w, const Mesh<dim>& m) {
  w.put<std::uint64_t>(static_cast<std::uint64_t>(m.num_nodes()));
  w.put_bytes(m.points.data(), sizeof(double) * static_cast<std::size_t>(m.points.size()));
  w.put<std::uint64_t>(m.cells.size());
  w.put_bytes(m.cells.data(), sizeof(m.cells[0]) * m.cells.size());
  w.put<std::uint64_t>(m.groups.size());
  for (const auto& [name, g] : m.groups) {
    w.put<std::uint64_t>(name.size());
    w.put_bytes(name.data(), name.size());
    w.put<std::uint64_t>(g.nodes.size());
    w.put_bytes(g.nodes.data(), sizeof(int) * g.nodes.size());
    w.put<std::uint64_t>(g.facets.size());
    w.put_bytes(g.facets.data(), sizeof(g.facets[0]) * g.facets.size());
  }
}

template <int dim> Mesh<dim> read_mesh(Reader& r, const std::string& src) {
  Mesh<dim> m;
  m.source = src;
  const std::size_t n = r.count(sizeof(double) * dim);
  m.points.resize(dim, static_cast<Eigen::Index>(n));
  r.get_bytes(m.points.data(), sizeof(double) * dim * n);
  m.cells.resize(r.count(sizeof(m.cells[0])));
  r.get_bytes(m.cells.data(), sizeof(m.cells[0]) * m.cells.size());
  const std::size_t groups = r.count(1);
  for (std::size_t k = 0; k < groups; ++k) {
    std::string name(r.count(1), '\0');
    r.get_bytes(name.data(), name.size());
    MeshGroup<dim> g;
    g.nodes.resize(r.count(sizeof(int)));
    r.get_bytes(g.nodes.data(), sizeof(int) * g.nodes.size());
    g.facets.resize(r.count(sizeof(g.facets[0])));
    r.get_bytes(g.facets.data(), sizeof(g.facets[0]) * g.facets.size());
    m.groups[name] = std::move(g);
  }
  return m;
}

} // namespace

std::string serialize(const AnyMesh& mesh) {
  Writer w;
  w.put<std::uint8_t>(static_cast<std::uint8_t>(dimension(mesh)));
  std::visit([&w](const auto& m) { write_mesh(w, m); }, mesh);
  return w.take();
}

AnyMesh deserialize(std::string_view bytes, const std::string& src) {
  Reader r(bytes, src);
  const auto dim = r.get<std::uint8_t>();
  if (dim == 2) return read_mesh<2>(r, src);
  if (dim == 3) return read_mesh<3>(r, src);
  throw InputError(src + ": corrupt mesh data from the reader");
}

} // namespace vtb
