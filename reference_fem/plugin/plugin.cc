// The FEM plugin (vtb_fem_plugin.so): vtb_fem, with deal.II linked, behind one exported
// function that returns the table of plugin_api.hh. Built with hidden visibility and
// -Bsymbolic, so that its copies of vtb's code bind to themselves and nothing of it leaks into
// the process that loads it.
#include "plugin_api.hh"

namespace {

void* mpi_begin(int& argc, char**& argv) {
  return new vtb::fem::MpiScope(argc, argv);
}
void mpi_end(void* scope) {
  delete static_cast<vtb::fem::MpiScope*>(scope);
}

constexpr vtb::fem::plugin::Api kApi{vtb::fem::plugin::kApiVersion,
                                     &vtb::fem::simulate<2>,
                                     &vtb::fem::simulate<3>,
                                     &vtb::fem::simulate_distributed<2>,
                                     &vtb::fem::simulate_distributed<3>,
                                     &vtb::fem::continuum_answers<2>,
                                     &vtb::fem::continuum_answers<3>,
                                     &vtb::fem::continuum_static<2>,
                                     &vtb::fem::continuum_static<3>,
                                     &vtb::fem::run_scene,
                                     &mpi_begin,
                                     &mpi_end};

} // namespace

extern "C" __attribute__((visibility("default"))) const vtb::fem::plugin::Api* vtb_fem_plugin_api() {
  return &kApi;
}
