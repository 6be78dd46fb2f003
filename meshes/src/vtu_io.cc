#include "vtb/meshes/vtu_io.hh"

#include "vtb/meshes/input_error.hh"

#include <fstream>
#include <iomanip>

namespace vtb {

template <int dim>
void write_vtu(const Mesh<dim>& mesh, const std::filesystem::path& file,
               const Eigen::Matrix<double, dim, Eigen::Dynamic>& disp) {
  const std::filesystem::path tmp = file.string() + ".part";
  {
    std::ofstream f(tmp);
    if (!f) throw InputError(file.string() + ": cannot write");
    f << std::setprecision(17);
    f << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << mesh.num_nodes() << "\" NumberOfCells=\"" << mesh.num_cells()
      << "\">\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (int i = 0; i < mesh.num_nodes(); ++i)
      f << mesh.points(0, i) << ' ' << mesh.points(1, i) << ' ' << (dim == 3 ? mesh.points(dim - 1, i) : 0.0) << '\n';
    f << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (const auto& c : mesh.cells) {
      for (int v : c) f << v << ' ';
      f << '\n';
    }
    f << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (int c = 1; c <= mesh.num_cells(); ++c) f << c * (dim + 1) << '\n';
    f << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (int c = 0; c < mesh.num_cells(); ++c) f << (dim == 2 ? 5 : 10) << '\n'; // VTK_TRIANGLE, VTK_TETRA
    f << "</DataArray>\n</Cells>\n";
    if (disp.cols() == mesh.num_nodes()) {
      f << "<PointData Vectors=\"displacement\">\n"
        << "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n";
      for (int i = 0; i < mesh.num_nodes(); ++i)
        f << disp(0, i) << ' ' << disp(1, i) << ' ' << (dim == 3 ? disp(dim - 1, i) : 0.0) << '\n';
      f << "</DataArray>\n</PointData>\n";
    }
    f << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    if (!f) throw InputError(file.string() + ": write failed");
  }
  std::filesystem::rename(tmp, file);
}

template void write_vtu<2>(const Mesh<2>&, const std::filesystem::path&,
                           const Eigen::Matrix<double, 2, Eigen::Dynamic>&);
template void write_vtu<3>(const Mesh<3>&, const std::filesystem::path&,
                           const Eigen::Matrix<double, 3, Eigen::Dynamic>&);

} // namespace vtb
