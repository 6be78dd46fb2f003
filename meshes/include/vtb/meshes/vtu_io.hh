#pragma once
/// \file
/// VTK XML unstructured grids (.vtu) for ParaView: the mesh with point and cell fields, as
/// zlib-compressed base64 binary (VTK's "binary" format with vtkZLibDataCompressor).

#include "vtb/meshes/mesh.hh"

#include <filesystem>
#include <string>
#include <vector>

namespace vtb {

/// A field written beside the mesh: `components` values per node (point data) or per cell.
struct VtuField {
  std::string name;
  int components = 1;
  bool per_cell = false;
  std::vector<double> values; ///< node- or cell-major, components contiguous
};

/// Writes `mesh` and the fields (a field with 2 components in 2D is written with 3, z = 0, so
/// that ParaView treats it as a vector). Written to FILE.part and renamed: no partial file.
template <int dim>
void write_vtu(const Mesh<dim>& mesh, const std::filesystem::path& file, const std::vector<VtuField>& fields = {});

/// A per-node vector field (dim rows) as a VtuField.
template <int dim> VtuField point_vectors(const std::string& name, const Eigen::Matrix<double, dim, Eigen::Dynamic>& v);

/// Base64 of bytes (RFC 4648, padded): VTK's inline binary encoding.
std::string base64(const unsigned char* data, std::size_t size);

} // namespace vtb
