// The gmsh API, built as a module of its own that vtb loads on demand (gmsh_backend.hh): the
// only file that includes gmsh.h.
#include "gmsh_backend.hh"

#include "vtb/base/input_error.hh"
#include "vtb/meshes/mesh_serialize.hh"

#include <gmsh.h>

#include <algorithm>
#include <unordered_map>

namespace vtb {
namespace {

/// The gmsh library keeps one model in process-wide state; this guard scopes it to one
/// read or write so that vtb itself holds no global.
class GmshSession {
public:
  GmshSession() {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.Verbosity", 1);
  }
  ~GmshSession() { gmsh::finalize(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  /// The last error gmsh logged, or "" if none.
  static std::string last_error() {
    std::string e;
    gmsh::logger::getLastError(e);
    return e;
  }
};

constexpr int kLine = 1, kTriangle = 2, kTetrahedron = 4, kPoint = 15;

std::string element_name(int type) {
  std::string name;
  int d = 0, order = 0, nn = 0, np = 0;
  std::vector<double> lc;
  try {
    gmsh::model::mesh::getElementProperties(type, name, d, order, nn, lc, np);
  } catch (...) {
    return "type " + std::to_string(type);
  }
  return name + " (type " + std::to_string(type) + ")";
}

/// The gmsh node block: tags, their index in the mesh, and the lookup that names a dangling tag.
struct NodeTable {
  std::string src;
  std::vector<std::size_t> tags;
  std::unordered_map<std::size_t, int> index;
  int at(std::size_t tag, const std::string& where) const {
    const auto it = index.find(tag);
    if (it == index.end())
      throw InputError(src + ": " + where + " refers to node tag " + std::to_string(tag) + ", which does not exist");
    return it->second;
  }
};

/// The nodes' coordinates into mesh.points; refuses a repeated tag and, in 2D, z != 0.
template <int dim> NodeTable read_nodes(const std::string& src, Mesh<dim>& mesh) {
  NodeTable nodes{src, {}, {}};
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(nodes.tags, coords, param, -1, -1, false, false);
  if (coords.size() != 3 * nodes.tags.size()) throw InputError(src + ": inconsistent node block");
  nodes.index.reserve(nodes.tags.size());
  mesh.points.resize(dim, static_cast<Eigen::Index>(nodes.tags.size()));
  for (std::size_t i = 0; i < nodes.tags.size(); ++i) {
    if (!nodes.index.emplace(nodes.tags[i], static_cast<int>(i)).second)
      throw InputError(src + ": node tag " + std::to_string(nodes.tags[i]) + " appears twice");
    for (int a = 0; a < dim; ++a)
      mesh.points(a, static_cast<Eigen::Index>(i)) = coords[3 * i + static_cast<std::size_t>(a)];
    if (dim == 2 && coords[3 * i + 2] != 0.0)
      throw InputError(src + ": node tag " + std::to_string(nodes.tags[i]) + " has z != 0 in a 2D mesh");
  }
  return nodes;
}

/// The top-dimensional cells (3-node triangles or 4-node tetrahedra; anything else is refused).
template <int dim> void read_cells(const NodeTable& nodes, Mesh<dim>& mesh) {
  using Cell = typename Mesh<dim>::Cell;
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> elem_tags, elem_nodes;
  gmsh::model::mesh::getElements(types, elem_tags, elem_nodes, dim, -1);
  const int cell_type = dim == 2 ? kTriangle : kTetrahedron;
  for (std::size_t t = 0; t < types.size(); ++t) {
    if (types[t] != cell_type)
      throw InputError(nodes.src + ": unsupported element " + element_name(types[t]) + " (element tag " +
                       std::to_string(elem_tags[t].empty() ? 0 : elem_tags[t][0]) + "); vtb reads " +
                       (dim == 2 ? "3-node triangles" : "4-node tetrahedra"));
    for (std::size_t e = 0; e < elem_tags[t].size(); ++e) {
      Cell c{};
      for (int v = 0; v <= dim; ++v)
        c[static_cast<std::size_t>(v)] = nodes.at(elem_nodes[t][e * (dim + 1) + static_cast<std::size_t>(v)],
                                                  "element tag " + std::to_string(elem_tags[t][e]));
      mesh.cells.push_back(c);
    }
  }
}

/// Drops the nodes that belong to no cell (e.g. geometry points); returns old index -> new
/// index (-1: dropped).
template <int dim> std::vector<int> drop_orphan_nodes(Mesh<dim>& mesh) {
  std::vector<int> remap(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (const auto& c : mesh.cells)
    for (int v : c) remap[static_cast<std::size_t>(v)] = 0;
  int kept = 0;
  for (auto& r : remap)
    if (r == 0) r = kept++;
  if (kept != mesh.num_nodes()) {
    Eigen::Matrix<double, dim, Eigen::Dynamic> pts(dim, kept);
    for (std::size_t i = 0; i < remap.size(); ++i)
      if (remap[i] >= 0) pts.col(remap[i]) = mesh.points.col(static_cast<Eigen::Index>(i));
    mesh.points = std::move(pts);
    for (auto& c : mesh.cells)
      for (int& v : c) v = remap[static_cast<std::size_t>(v)];
  }
  return remap;
}

/// One physical group of lower dimension: its nodes and, for facets, the facets.
template <int dim>
MeshGroup<dim> read_group(const NodeTable& nodes, const std::vector<int>& remap, int gdim, int gtag,
                          const std::string& name) {
  using Facet = typename Mesh<dim>::Facet;
  MeshGroup<dim> g;
  std::vector<int> entities;
  gmsh::model::getEntitiesForPhysicalGroup(gdim, gtag, entities);
  for (int ent : entities) {
    std::vector<int> gt;
    std::vector<std::vector<std::size_t>> gtags, gnodes;
    gmsh::model::mesh::getElements(gt, gtags, gnodes, gdim, ent);
    for (std::size_t t = 0; t < gt.size(); ++t) {
      const int nv = gt[t] == kPoint ? 1 : gt[t] == kLine ? 2 : gt[t] == kTriangle ? 3 : -1;
      if (nv < 0 || (gdim == dim - 1 && nv != dim))
        throw InputError(nodes.src + ": group \"" + name + "\" holds unsupported element " + element_name(gt[t]));
      for (std::size_t e = 0; e < gtags[t].size(); ++e) {
        Facet f{};
        for (int v = 0; v < nv; ++v) {
          const int local = nodes.at(gnodes[t][e * static_cast<std::size_t>(nv) + static_cast<std::size_t>(v)],
                                     "group \"" + name + "\"");
          const int idx = remap[static_cast<std::size_t>(local)];
          if (idx < 0)
            throw InputError(nodes.src + ": group \"" + name + "\" uses node tag " +
                             std::to_string(nodes.tags[static_cast<std::size_t>(local)]) +
                             ", which belongs to no cell");
          g.nodes.push_back(idx);
          if (nv == dim) f[static_cast<std::size_t>(v)] = idx;
        }
        if (gdim == dim - 1) g.facets.push_back(f);
      }
    }
  }
  return g;
}

/// Every physical group below the domain's dimension, merged by name (unnamed ones are
/// called "DIM_TAG").
template <int dim> void read_groups(const NodeTable& nodes, const std::vector<int>& remap, Mesh<dim>& mesh) {
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, -1);
  for (const auto& [gdim, gtag] : groups) {
    if (gdim == dim) continue; // the domain itself
    std::string name;
    gmsh::model::getPhysicalName(gdim, gtag, name);
    if (name.empty()) name = std::to_string(gdim) + "_" + std::to_string(gtag);
    const MeshGroup<dim> g = read_group<dim>(nodes, remap, gdim, gtag, name);
    auto& slot = mesh.groups[name];
    slot.nodes.insert(slot.nodes.end(), g.nodes.begin(), g.nodes.end());
    std::sort(slot.nodes.begin(), slot.nodes.end());
    slot.nodes.erase(std::unique(slot.nodes.begin(), slot.nodes.end()), slot.nodes.end());
    slot.facets.insert(slot.facets.end(), g.facets.begin(), g.facets.end());
  }
}

template <int dim> AnyMesh read_dim(const std::string& src) {
  Mesh<dim> mesh;
  mesh.source = src;
  const NodeTable nodes = read_nodes(src, mesh);
  read_cells(nodes, mesh);
  const std::vector<int> remap = drop_orphan_nodes(mesh);
  read_groups(nodes, remap, mesh);
  return mesh;
}

/// Reads with gmsh in this process (no isolation).
AnyMesh read_msh_in_process(const std::string& src) {
  GmshSession session;
  // The gmsh API reports errors by throwing std::string (and logging them).
  try {
    gmsh::open(src);
    if (const std::string e = GmshSession::last_error(); !e.empty()) throw e;
    // The mesh dimension is the highest dimension holding elements.
    std::vector<int> t3, t2;
    std::vector<std::vector<std::size_t>> a, b;
    gmsh::model::mesh::getElements(t3, a, b, 3, -1);
    if (!t3.empty()) return read_dim<3>(src);
    gmsh::model::mesh::getElements(t2, a, b, 2, -1);
    if (!t2.empty()) return read_dim<2>(src);
  } catch (const std::string& e) {
    throw InputError(src + ": gmsh cannot read it: " + e);
  } catch (int) {
    const std::string e = GmshSession::last_error();
    throw InputError(src + ": gmsh cannot read it" + (e.empty() ? "" : ": " + e));
  }
  throw InputError(src + ": no triangles or tetrahedra in the file");
}

template <int dim> void write_with_gmsh(const Mesh<dim>& mesh, const std::string& path) {
  GmshSession session;
  gmsh::model::add("vtb");
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  const int domain = gmsh::model::addDiscreteEntity(dim, 1);
  std::vector<std::size_t> tags(static_cast<std::size_t>(mesh.num_nodes()));
  std::vector<double> xyz(3 * tags.size(), 0.0);
  for (std::size_t i = 0; i < tags.size(); ++i) {
    tags[i] = i + 1;
    for (int a = 0; a < dim; ++a)
      xyz[3 * i + static_cast<std::size_t>(a)] = mesh.points(a, static_cast<Eigen::Index>(i));
  }
  gmsh::model::mesh::addNodes(dim, domain, tags, xyz);
  std::vector<std::size_t> etags, enodes;
  std::size_t next = 1;
  for (const auto& c : mesh.cells) {
    etags.push_back(next++);
    for (int v : c) enodes.push_back(static_cast<std::size_t>(v) + 1);
  }
  gmsh::model::mesh::addElementsByType(domain, dim == 2 ? kTriangle : kTetrahedron, etags, enodes);
  gmsh::model::setPhysicalName(dim, gmsh::model::addPhysicalGroup(dim, {domain}), "domain");
  int entity = 1;
  for (const auto& [name, g] : mesh.groups) {
    if (g.facets.empty()) continue; // node-only groups are not representable as facets
    const int ent = gmsh::model::addDiscreteEntity(dim - 1, entity++);
    std::vector<std::size_t> ft, fn;
    for (const auto& f : g.facets) {
      ft.push_back(next++);
      for (int v : f) fn.push_back(static_cast<std::size_t>(v) + 1);
    }
    gmsh::model::mesh::addElementsByType(ent, dim == 2 ? kLine : kTriangle, ft, fn);
    gmsh::model::setPhysicalName(dim - 1, gmsh::model::addPhysicalGroup(dim - 1, {ent}), name);
  }
  gmsh::write(path);
}

/// The write's error, or "" (gmsh reports errors by throwing std::string).
template <int dim> void write_reporting(const Mesh<dim>* mesh, const char* path, std::string* error) {
  try {
    write_with_gmsh(*mesh, path);
    error->clear();
  } catch (const std::string& e) {
    *error = e.empty() ? "gmsh failed" : e;
  } catch (const std::exception& e) {
    *error = e.what();
  } catch (...) {
    *error = "gmsh failed";
  }
}

} // namespace
} // namespace vtb

extern "C" {

__attribute__((visibility("default"))) void vtb_gmsh_read(const char* src, std::string* out) {
  try {
    *out = "M" + vtb::serialize(vtb::read_msh_in_process(src));
  } catch (const std::exception& e) {
    *out = std::string("E") + e.what();
  }
}

__attribute__((visibility("default"))) void vtb_gmsh_write2(const vtb::Mesh<2>* mesh, const char* path,
                                                            std::string* error) {
  vtb::write_reporting(mesh, path, error);
}

__attribute__((visibility("default"))) void vtb_gmsh_write3(const vtb::Mesh<3>* mesh, const char* path,
                                                            std::string* error) {
  vtb::write_reporting(mesh, path, error);
}

} // extern "C"
