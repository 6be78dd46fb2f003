#include "vtb/meshes/generate.hh"

#include "vtb/base/input_error.hh"

#include <algorithm>

namespace vtb {
namespace {

template <int dim> void add_face_group(Mesh<dim>& mesh, const std::string& name, int axis, double value) {
  MeshGroup<dim> g;
  const double tol = 1e-12 * bounding_diagonal(mesh);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (std::abs(mesh.points(axis, i) - value) <= tol) g.nodes.push_back(i);
  for (const auto& f : boundary_facets(mesh))
    if (std::all_of(f.begin(), f.end(), [&](int v) { return std::abs(mesh.points(axis, v) - value) <= tol; }))
      g.facets.push_back(f);
  mesh.groups[name] = std::move(g);
}

template <int dim>
void check_request(const Eigen::Matrix<double, dim, 1>& size, const Eigen::Matrix<int, dim, 1>& div, const char* what) {
  if (!(size.array() > 0).all() || !size.allFinite())
    throw InputError(std::string(what) + ": size must be positive and finite");
  if (!(div.array() >= 1).all()) throw InputError(std::string(what) + ": divisions must be >= 1");
  if (div.template cast<double>().prod() > 5e7) throw InputError(std::string(what) + ": too many divisions");
}

} // namespace

Mesh2 generate_rectangle(const Eigen::Vector2d& size, const Eigen::Vector2i& div) {
  check_request<2>(size, div, "rectangle");
  Mesh2 m;
  m.source = "generated rectangle";
  const int nx = div.x() + 1, ny = div.y() + 1;
  m.points.resize(2, nx * ny);
  auto id = [nx](int i, int j) { return j * nx + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.points.col(id(i, j)) << size.x() * i / div.x(), size.y() * j / div.y();
  for (int j = 0; j < div.y(); ++j) {
    for (int i = 0; i < div.x(); ++i) {
      // Corners of the square in local coordinates, mirrored on odd rows/columns.
      auto c = [&](int a, int b) {
        const int li = (i % 2 == 1) ? 1 - a : a;
        const int lj = (j % 2 == 1) ? 1 - b : b;
        return id(i + li, j + lj);
      };
      // Kuhn split along the local diagonal (0,0)-(1,1).
      m.cells.push_back({c(0, 0), c(1, 0), c(1, 1)});
      m.cells.push_back({c(0, 0), c(1, 1), c(0, 1)});
    }
  }
  check_and_orient(m);
  add_face_group(m, "left", 0, 0.0);
  add_face_group(m, "right", 0, size.x());
  add_face_group(m, "bottom", 1, 0.0);
  add_face_group(m, "top", 1, size.y());
  return m;
}

Mesh3 generate_box(const Eigen::Vector3d& size, const Eigen::Vector3i& div) {
  check_request<3>(size, div, "box");
  Mesh3 m;
  m.source = "generated box";
  const int nx = div.x() + 1, ny = div.y() + 1, nz = div.z() + 1;
  m.points.resize(3, nx * ny * nz);
  auto id = [nx, ny](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        m.points.col(id(i, j, k)) << size.x() * i / div.x(), size.y() * j / div.y(), size.z() * k / div.z();
  // Kuhn: the six monotone paths from (0,0,0) to (1,1,1), one tetrahedron each.
  static constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < div.z(); ++k)
    for (int j = 0; j < div.y(); ++j)
      for (int i = 0; i < div.x(); ++i) {
        const int cell[3] = {i, j, k};
        auto corner = [&](const std::array<int, 3>& local) {
          std::array<int, 3> g{};
          for (int a = 0; a < 3; ++a) g[a] = cell[a] + ((cell[a] % 2 == 1) ? 1 - local[a] : local[a]);
          return id(g[0], g[1], g[2]);
        };
        for (const auto& p : perms) {
          std::array<int, 3> l{0, 0, 0};
          Mesh3::Cell t{};
          t[0] = corner(l);
          for (int s = 0; s < 3; ++s) {
            l[p[s]] = 1;
            t[s + 1] = corner(l);
          }
          m.cells.push_back(t);
        }
      }
  check_and_orient(m);
  add_face_group(m, "left", 0, 0.0);
  add_face_group(m, "right", 0, size.x());
  add_face_group(m, "bottom", 1, 0.0);
  add_face_group(m, "top", 1, size.y());
  add_face_group(m, "front", 2, 0.0);
  add_face_group(m, "back", 2, size.z());
  return m;
}

} // namespace vtb
