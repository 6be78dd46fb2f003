#pragma once
/// \file
/// What the spring solvers simulate: the scene's Problem and the spring network made from it.

#include "vtb/problem/problem.hh"
#include "vtb/problem/run_report.hh"
#include "vtb/springs/load_check.hh"
#include "vtb/springs/spring_network.hh"

namespace vtb {

template <int dim> struct Model : Problem<dim> { SpringNetwork<dim> net; };

/// The problem (build_problem) and its spring network ([solver].springs calibration;
/// `progress` is told how a fit advances). With `check_loads` false the springs' error on the
/// scene's loads (static_load_error) is not measured and stays NaN: a caller that measured it
/// for the same mesh, supports, loads, Poisson ratio and springs already has it (it does not
/// change with Young's modulus, dt or the solver). `yardstick`: what the check measures the
/// springs against (load_check.hh): the continuum where given and within its budget, else P1
/// on the mesh.
template <int dim>
Model<dim> build_model(const Scene& scene, Mesh<dim> mesh, const FitProgress& progress = {}, bool check_loads = true,
                       const Yardstick* yardstick = nullptr);

/// What every spring solver reports alike (the integrators and CVODE): the solver's name, the
/// sizes, the duration and the calibration (its name, wall time, whether it came from the
/// cache, and the Poisson ratio the lattice implies).
template <int dim> RunReport spring_report(const Model<dim>& model, const std::string& solver);

/// Loads the scene's mesh, builds the model in the mesh's dimension and returns f(model); f
/// takes a `Model<2>&` and a `Model<3>&` (a generic lambda; Model<dim>::dimension names dim)
/// and may move the model away. `progress`, `yardstick`: as build_model's.
template <class F>
auto with_model(const Scene& scene, F&& f, const FitProgress& progress = {}, const Yardstick* yardstick = nullptr) {
  return with_mesh(scene, [&](auto& m) {
    constexpr int dim = std::decay_t<decltype(m)>::points_dim;
    Model<dim> model = build_model<dim>(scene, std::move(m), progress, true, yardstick);
    return f(model);
  });
}

} // namespace vtb
