#pragma once
/// \file
/// Every solver of the testbed behind one call, for the harness: the spring integrators,
/// CVODE and the deal.II reference, each recording the full nodal field at sample times.

#include "vtb/solvers/simulation.hh"

namespace vtb::harness {

/// Runs `solver` on the model (its dt from the scene unless `dt` > 0; explicit defaults to
/// half its predicted stability limit when the scene's dt is above it).
template <int dim>
RunReport run_solver(const Scene& scene, const Model<dim>& model, const std::string& solver, double dt,
                     Trajectory<dim>& out);

} // namespace vtb::harness
