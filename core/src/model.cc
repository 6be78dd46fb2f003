#include "vtb/core/model.hh"

namespace vtb {

template <int dim> Model<dim> build_model(const Scene& scene, Mesh<dim> mesh) {
  Model<dim> model;
  static_cast<Problem<dim>&>(model) = build_problem<dim>(scene, std::move(mesh));
  model.net = build_network(model.mesh, scene.material, scene.solver.springs);
  return model;
}

template Model<2> build_model<2>(const Scene&, Mesh<2>);
template Model<3> build_model<3>(const Scene&, Mesh<3>);

} // namespace vtb
