#include "commands.hh"

#include "vtb/base/input_error.hh"
#include "vtb/meshes/cgal_generate.hh" // Refinement, refinement_error: declarations only without CGAL
#include "vtb/meshes/generate.hh"
#include "vtb/meshes/msh_io.hh"
#include "vtb/meshes/quality.hh"
#ifdef VTB_HAVE_CGAL_MESHERS
#include "vtb/meshes/surface.hh"
#endif
#include "vtb/meshes/vtu_io.hh"

#include <iostream>
#include <memory>

namespace vtb::cli {

namespace {

template <int dim> void print_info(const Mesh<dim>& m) {
  double vmin = 1e300, vmax = 0;
  for (const auto& c : m.cells) {
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
  const MeshQuality q = mesh_quality(m);
  std::cout << (dim == 2 ? "angle" : "dihedral angle") << " min/max: " << q.min_angle << " / " << q.max_angle
            << " deg\n"
            << "radius-edge ratio max: " << q.max_radius_edge << "\n"
            << "inverted: " << q.inverted << "\n"
            << "degenerate: " << q.degenerate << "\n";
  for (const auto& [name, g] : m.groups)
    std::cout << "group " << name << ": " << g.nodes.size() << " nodes, " << g.facets.size() << " facets\n";
}

} // namespace

namespace {

struct MeshOpts {
  std::string file, shape, out, in;
  std::vector<double> size;
  std::vector<int> divisions;
  int nodes = 0;
  double hole = 0;
  std::string surface;
  double scale = 1;
  std::vector<double> refine_near, refine_radius, refine_size;
  double refine_growth = kRefineGrowth;
};

/// The --refine-near/--refine-radius/--refine-size triples (each option once per refinement).
std::vector<Refinement> refinements(const MeshOpts& o) {
  const std::size_t n = o.refine_near.size() / 3;
  if (o.refine_near.size() % 3 != 0 || o.refine_radius.size() != n || o.refine_size.size() != n)
    throw InputError("vtb mesh generate " + o.shape +
                     ": each refinement needs --refine-near X,Y,Z, --refine-radius R and --refine-size h");
  std::vector<Refinement> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i].center = Eigen::Vector3d(o.refine_near[3 * i], o.refine_near[3 * i + 1], o.refine_near[3 * i + 2]);
    out[i].radius = o.refine_radius[i];
    out[i].size = o.refine_size[i];
    out[i].growth = o.refine_growth;
    if (const std::string why = refinement_error(out[i]); !why.empty())
      throw InputError("vtb mesh generate " + o.shape + ": refinement " + std::to_string(i) + ": " + why);
  }
  return out;
}

#ifdef VTB_HAVE_CGAL_MESHERS
/// `vtb mesh generate surface FILE`: a closed surface's inside (surface.hh, mesh_surface).
void generate_surface(const MeshOpts& o, const std::vector<Refinement>& refine) {
  if (o.surface.empty()) throw InputError("vtb mesh generate surface: the surface FILE is required");
  if (o.size.size() > 1) throw InputError("vtb mesh generate surface: --size takes one element size (m)");
  const double h = o.size.empty() ? 0 : o.size[0];
  if ((o.nodes > 0) == (h > 0))
    throw InputError("vtb mesh generate surface: give --nodes N or --size H (one of them, > 0)");
  const std::filesystem::path file(o.surface);
  write_msh(mesh_surface(read_surface(file, o.scale), o.nodes, h, refine, file.filename().string()), o.out);
}
#endif

/// The shapes CGAL meshes: the paper's plate, the Mesh_3 slab and sphere, a surface's inside, and
/// an unstructured rectangle or box (--nodes).
void generate_cgal(const MeshOpts& o, const std::vector<Refinement>& refine) {
#ifdef VTB_HAVE_CGAL_MESHERS
  if (o.shape == "surface") return generate_surface(o, refine);
  if (o.shape == "plate" || o.shape == "slab" || o.shape == "sphere") {
    if (o.nodes <= 0) throw InputError("vtb mesh generate " + o.shape + ": --nodes N (N > 0) is required");
    if (o.shape == "plate")
      write_msh(mesh_polygon(paper_plate(), o.nodes), o.out);
    else
      write_msh(mesh_solid(o.shape, o.nodes, refine), o.out);
    return;
  }
  const std::size_t d = o.shape == "rectangle" ? 2 : 3;
  if (o.size.size() != d || !o.divisions.empty())
    throw InputError("vtb mesh generate " + o.shape + " --nodes N: needs --size with " + std::to_string(d) +
                     " values and no --divisions");
  if (d == 2)
    write_msh(mesh_rectangle(Eigen::Vector2d(o.size[0], o.size[1]), o.nodes, o.hole), o.out);
  else
    write_msh(mesh_box(Eigen::Vector3d(o.size[0], o.size[1], o.size[2]), o.nodes, refine), o.out);
#else
  (void)refine;
  throw InputError("vtb mesh generate " + o.shape +
                   ": this build has no CGAL meshers (VTB_WITH_CGAL=OFF); a structured rectangle or box "
                   "(--size, --divisions) needs none");
#endif
}

/// `vtb mesh convert IN OUT`: a .msh (2.2 or 4.x) to .msh 4.1 or .vtu.
void convert_mesh(const MeshOpts& o) {
  const std::filesystem::path out(o.out);
  if (out.extension() != ".msh" && out.extension() != ".vtu")
    throw InputError("vtb mesh convert: output " + o.out + " must end in .msh or .vtu");
  std::visit(
      [&](const auto& mesh) {
        if (out.extension() == ".vtu")
          write_vtu(mesh, out);
        else
          write_msh(mesh, out);
      },
      read_msh(o.in));
}

/// `vtb mesh generate SHAPE ...`: the CGAL plate and solids, an unstructured (CGAL) rectangle
/// or box with --nodes, or a structured one with --divisions.
void generate_mesh(const MeshOpts& o) {
  const std::vector<Refinement> refine = refinements(o);
  if (!o.surface.empty() && o.shape != "surface")
    throw InputError("vtb mesh generate " + o.shape + ": a FILE is for shape surface");
  if (o.scale != 1 && o.shape != "surface")
    throw InputError("vtb mesh generate " + o.shape + ": --scale is for shape surface");
  if (!refine.empty() && o.shape != "surface" && o.shape != "slab" && o.shape != "sphere" &&
      !(o.shape == "box" && o.nodes > 0))
    throw InputError("vtb mesh generate " + o.shape + ": refinement is for surface, slab, sphere and a CGAL box");
  const std::size_t d = o.shape == "rectangle" ? 2 : 3;
  if (o.hole != 0 && (d != 2 || o.nodes <= 0))
    throw InputError("vtb mesh generate " + o.shape + ": --hole is for an unstructured rectangle (--nodes)");
  if (o.hole < 0) throw InputError("vtb mesh generate " + o.shape + ": --hole must be > 0");
  if (o.shape == "surface" || o.shape == "plate" || o.shape == "slab" || o.shape == "sphere" || o.nodes > 0)
    return generate_cgal(o, refine);
  if (o.size.size() != d || o.divisions.size() != d)
    throw InputError("vtb mesh generate " + o.shape + ": --size and --divisions need " + std::to_string(d) + " values");
  if (d == 2)
    write_msh(
        generate_rectangle(Eigen::Vector2d(o.size[0], o.size[1]), Eigen::Vector2i(o.divisions[0], o.divisions[1])),
        o.out);
  else
    write_msh(generate_box(Eigen::Vector3d(o.size[0], o.size[1], o.size[2]),
                           Eigen::Vector3i(o.divisions[0], o.divisions[1], o.divisions[2])),
              o.out);
}

} // namespace

Action add_mesh(CLI::App& app) {
  auto o = std::make_shared<MeshOpts>();
  CLI::App* cmd = app.add_subcommand("mesh", "Generate or inspect meshes");
  cmd->require_subcommand(1);
  CLI::App* info = cmd->add_subcommand("info", "Print counts, groups and sizes of a .msh file");
  info->add_option("file", o->file, "Mesh file (.msh)")->required();
  CLI::App* gen = cmd->add_subcommand(
      "generate", "Write a mesh as .msh 4.1: structured rectangle/box (--size, --divisions), the paper's plate "
                  "(CGAL, exact --nodes), a CGAL Mesh_3 slab/sphere (about --nodes), or the inside of a closed "
                  "surface FILE (.off, .stl, .obj, .ply; --nodes or --size)");
  gen->add_option("shape", o->shape, "rectangle | box | plate | slab | sphere | surface")
      ->required()
      ->check(CLI::IsMember({"rectangle", "box", "plate", "slab", "sphere", "surface"}));
  gen->add_option("file", o->surface, "Closed surface (shape surface): .off, .stl, .obj or .ply");
  gen->add_option("--size", o->size, "Extent per axis (m), rectangle and box; the element size (m), surface");
  gen->add_option("--scale", o->scale, "Multiplies the surface's coordinates (e.g. 0.001 for a file in mm)");
  gen->add_option("--refine-near", o->refine_near, "X,Y,Z (m): grade the mesh toward this point (repeatable)")
      ->delimiter(',')
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  gen->add_option("--refine-radius", o->refine_radius, "R (m): element size --refine-size within R of the point")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  gen->add_option("--refine-size", o->refine_size,
                  "h (m): the element size near the point; it grows by --refine-growth m per m beyond R to the "
                  "body's")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  gen->add_option("--refine-growth", o->refine_growth,
                  "m of element size per m of distance beyond R, in (0, 1], every refinement (default 0.25; slower "
                  "costs nodes, moves the answers less: docs/meshes.md)");
  gen->add_option("--divisions", o->divisions, "Cells per axis, rectangle and box");
  gen->add_option("--nodes", o->nodes,
                  "Node count: exact for plate and an unstructured rectangle, approximate (15 %) for slab, sphere "
                  "and an unstructured box");
  gen->add_option("--hole", o->hole,
                  "Radius (m) of a circular hole at the centre of an unstructured rectangle (group \"hole\")");
  gen->add_option("-o,--out", o->out, "Output .msh file")->required();
  CLI::App* conv = cmd->add_subcommand("convert", "Convert a .msh (2.2 or 4.x) to .msh 4.1 or .vtu");
  conv->add_option("in", o->in, "Input .msh")->required();
  conv->add_option("out", o->out, "Output .msh or .vtu")->required();
  return [o, info, gen, conv]() {
    if (info->parsed()) {
      std::visit([](const auto& m) { print_info(m); }, read_msh(o->file));
      return 0;
    }
    if (conv->parsed()) convert_mesh(*o);
    if (gen->parsed()) generate_mesh(*o);
    std::cout << "wrote " << o->out << "\n";
    return 0;
  };
}

} // namespace vtb::cli
