// The FEM's functions as the rest of vtb calls them (vtb/fem/*.hh): each loads the FEM plugin
// (plugin.cc: vtb_fem and deal.II) for the call and forwards to it, so that deal.II enters a
// process only when a FEM runs (vtb/base/module.hh: where it is looked for, and why it stays
// loaded once in).
#include "plugin_api.hh"
#include "vtb/base/atomic_file.hh"
#include "vtb/base/module.hh"

#include <mpi.h>

#include <cstdlib>
#include <string>

namespace vtb::fem {
namespace {

/// The plugin, opened for as long as this object lives.
class Plugin {
public:
  Plugin() : m_module("vtb_fem_plugin.so", VTB_FEM_PLUGIN, "the FEM reference") {
    const auto entry = reinterpret_cast<plugin::EntryPoint>(m_module.symbol(plugin::kEntryPoint));
    m_api = entry ? entry() : nullptr;
    if (!m_api || m_api->version != plugin::kApiVersion)
      throw IoError("the FEM reference (vtb_fem_plugin.so) is of another build than this program: rebuild vtb");
  }
  const plugin::Api& api() const { return *m_api; }

private:
  Module m_module;
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
