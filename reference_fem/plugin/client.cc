// The FEM's functions as the rest of vtb calls them (vtb/fem/*.hh): each loads the FEM plugin
// (plugin.cc: vtb_fem and deal.II) for the call and forwards to it, so that deal.II enters a
// process only when a FEM runs. The plugin is looked for in ../lib beside the program (or the
// library) that holds this code, then at the path the build wrote it to (VTB_FEM_PLUGIN).
// Loaded with RTLD_NODELETE: once in, deal.II stays (its static state outlives a call, and
// MPI cannot be initialised twice), and a second call only finds it again.
#include "plugin_api.hh"
#include "vtb/meshes/atomic_file.hh"

#include <dlfcn.h>
#include <mpi.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace vtb::fem {
namespace {

/// The plugin, opened for as long as this object lives.
class Plugin {
public:
  Plugin() {
    std::string tried;
    for (const std::string& path : candidates()) {
      m_handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
      if (m_handle) break;
      const char* why = dlerror();
      tried += (tried.empty() ? "" : "; ") + std::string(why ? why : path.c_str());
    }
    if (!m_handle) throw IoError("the FEM reference (vtb_fem_plugin.so) could not be loaded: " + tried);
    const auto entry = reinterpret_cast<plugin::EntryPoint>(dlsym(m_handle, plugin::kEntryPoint));
    m_api = entry ? entry() : nullptr;
    if (!m_api || m_api->version != plugin::kApiVersion) {
      dlclose(m_handle);
      throw IoError("the FEM reference (vtb_fem_plugin.so) is of another build than this program: rebuild vtb");
    }
  }
  ~Plugin() { dlclose(m_handle); }
  Plugin(const Plugin&) = delete;
  Plugin& operator=(const Plugin&) = delete;
  const plugin::Api& api() const { return *m_api; }

private:
  /// ../lib/vtb_fem_plugin.so from the folder of the object holding this code, then the build's.
  static std::vector<std::string> candidates() {
    std::vector<std::string> paths;
    Dl_info info{};
    if (dladdr(reinterpret_cast<const void*>(&mpi_rank), &info) && info.dli_fname) {
      std::string self = info.dli_fname;
      const auto slash = self.rfind('/');
      self = slash == std::string::npos ? "." : self.substr(0, slash);
      paths.push_back(self + "/../lib/vtb_fem_plugin.so");
    }
    paths.emplace_back(VTB_FEM_PLUGIN);
    return paths;
  }

  void* m_handle = nullptr;
  const plugin::Api* m_api = nullptr;
};

} // namespace

template <int dim>
RunReport simulate(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                   Trajectory<dim>& out, bool record_field) {
  check_options(options); // a bad option costs no deal.II
  const Plugin fem;
  if constexpr (dim == 2)
    return fem.api().simulate2(model, material, options, out, record_field);
  else
    return fem.api().simulate3(model, material, options, out, record_field);
}

template <int dim>
RunReport simulate_distributed(const Problem<dim>& model, const MaterialDesc& material, const FemOptions& options,
                               Trajectory<dim>& out, bool record_field) {
  check_options(options);
  const Plugin fem;
  if constexpr (dim == 2)
    return fem.api().simulate_distributed2(model, material, options, out, record_field);
  else
    return fem.api().simulate_distributed3(model, material, options, out, record_field);
}

template <int dim>
std::optional<ContinuumAnswers> continuum_answers(const Problem<dim>& problem, const MaterialDesc& material,
                                                  const Eigen::MatrixXd& F, const ContinuumOptions& options) {
  // Past the budget the answer is known without deal.II.
  if (continuum_first_dofs(problem.mesh) > continuum_budget(dim, options)) return std::nullopt;
  const Plugin fem;
  if constexpr (dim == 2)
    return fem.api().continuum_answers2(problem, material, F, options);
  else
    return fem.api().continuum_answers3(problem, material, F, options);
}

template <int dim>
std::optional<ContinuumAnswer<dim>> continuum_static(const Problem<dim>& problem, const MaterialDesc& material,
                                                     const ContinuumOptions& options) {
  if (continuum_first_dofs(problem.mesh) > continuum_budget(dim, options)) return std::nullopt;
  const Plugin fem;
  if constexpr (dim == 2)
    return fem.api().continuum_static2(problem, material, options);
  else
    return fem.api().continuum_static3(problem, material, options);
}

RunReport run_scene(const Scene& scene, const std::filesystem::path& out_dir, bool frames, RunTables* tables) {
  check_options(options_from(scene.solver));
  const Plugin fem;
  return fem.api().run_scene(scene, out_dir, frames, tables);
}

/// Under a launcher the plugin initialises MPI through deal.II and stays loaded until the end;
/// otherwise nothing is loaded.
struct MpiScope::Impl {
  std::unique_ptr<Plugin> fem;
  void* scope = nullptr;
};

MpiScope::MpiScope(int& argc, char**& argv) : m_impl(std::make_unique<Impl>()) {
  if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMI_SIZE")) return;
  m_impl->fem = std::make_unique<Plugin>();
  m_impl->scope = m_impl->fem->api().mpi_begin(argc, argv);
}
MpiScope::~MpiScope() {
  if (m_impl->fem) m_impl->fem->api().mpi_end(m_impl->scope);
}

int mpi_size() {
  int initialized = 0, finalized = 0, size = 1;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (initialized && !finalized) MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}
int mpi_rank() {
  int initialized = 0, finalized = 0, rank = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (initialized && !finalized) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

template RunReport simulate<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&, bool);
template RunReport simulate<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&, bool);
template RunReport simulate_distributed<2>(const Problem<2>&, const MaterialDesc&, const FemOptions&, Trajectory<2>&,
                                           bool);
template RunReport simulate_distributed<3>(const Problem<3>&, const MaterialDesc&, const FemOptions&, Trajectory<3>&,
                                           bool);
template std::optional<ContinuumAnswers> continuum_answers<2>(const Problem<2>&, const MaterialDesc&,
                                                              const Eigen::MatrixXd&, const ContinuumOptions&);
template std::optional<ContinuumAnswers> continuum_answers<3>(const Problem<3>&, const MaterialDesc&,
                                                              const Eigen::MatrixXd&, const ContinuumOptions&);
template std::optional<ContinuumAnswer<2>> continuum_static<2>(const Problem<2>&, const MaterialDesc&,
                                                               const ContinuumOptions&);
template std::optional<ContinuumAnswer<3>> continuum_static<3>(const Problem<3>&, const MaterialDesc&,
                                                               const ContinuumOptions&);

} // namespace vtb::fem
