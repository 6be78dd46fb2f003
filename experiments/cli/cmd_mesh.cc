#include "commands.hh"

#include "vtb/meshes/generate.hh"
#include "vtb/meshes/input_error.hh"
#include "vtb/meshes/msh_io.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

namespace {

template <int dim> void print_info(const Mesh<dim> &m) {
  double vmin = 1e300, vmax = 0;
  for (const auto &c : m.cells) {
    const double v = signed_measure(m, c);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  }
  std::cout << "mesh: " << m.source << "\n"
            << "dimension: " << dim << "\n"
            << "nodes: " << m.num_nodes() << "\n"
            << (dim == 2 ? "triangles: " : "tetrahedra: ") << m.num_cells() << "\n"
            << "edges: " << unique_edges(m).size() << "\n"
            << "boundary facets: " << boundary_facets(m).size() << "\n"
            << (dim == 2 ? "area" : "volume") << " min/max: " << vmin << " / " << vmax << "\n"
            << "bounding box: [" << m.points.rowwise().minCoeff().transpose() << "] - ["
            << m.points.rowwise().maxCoeff().transpose() << "]\n";
  for (const auto &[name, g] : m.groups)
    std::cout << "group " << name << ": " << g.nodes.size() << " nodes, " << g.facets.size() << " facets\n";
}

} // namespace

Action add_mesh(CLI::App &app) {
  struct Opts {
    std::string file, shape, out;
    std::vector<double> size;
    std::vector<int> divisions;
  };
  auto o = std::make_shared<Opts>();
  CLI::App *cmd = app.add_subcommand("mesh", "Generate or inspect meshes");
  cmd->require_subcommand(1);
  CLI::App *info = cmd->add_subcommand("info", "Print counts, groups and sizes of a .msh file");
  info->add_option("file", o->file, "Mesh file (.msh)")->required();
  CLI::App *gen = cmd->add_subcommand("generate", "Write a structured rectangle (2D) or box (3D) as .msh 4.1");
  gen->add_option("shape", o->shape, "rectangle | box")->required()->check(CLI::IsMember({"rectangle", "box"}));
  gen->add_option("--size", o->size, "Extent per axis (m)")->required();
  gen->add_option("--divisions", o->divisions, "Cells per axis")->required();
  gen->add_option("-o,--out", o->out, "Output .msh file")->required();
  return [o, info, gen]() {
    if (info->parsed()) {
      std::visit([](const auto &m) { print_info(m); }, read_msh(o->file));
      return 0;
    }
    if (gen->parsed()) {
      const std::size_t d = o->shape == "rectangle" ? 2 : 3;
      if (o->size.size() != d || o->divisions.size() != d)
        throw InputError("vtb mesh generate " + o->shape + ": --size and --divisions need " + std::to_string(d) +
                         " values");
      if (d == 2)
        write_msh(generate_rectangle(Eigen::Vector2d(o->size[0], o->size[1]),
                                     Eigen::Vector2i(o->divisions[0], o->divisions[1])),
                  o->out);
      else
        write_msh(generate_box(Eigen::Vector3d(o->size[0], o->size[1], o->size[2]),
                               Eigen::Vector3i(o->divisions[0], o->divisions[1], o->divisions[2])),
                  o->out);
      std::cout << "wrote " << o->out << "\n";
    }
    return 0;
  };
}

} // namespace vtb::cli
