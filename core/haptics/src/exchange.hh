#pragma once
/// \file
/// What the physics and the servo threads of a haptics session share, each through a lock-free
/// triple buffer (triple_buffer.hh): the physics publishes the deformed body with each probe's
/// local contact model (local_model.hh); the servo sends back each probe's contact.

#include "vtb/haptics/contact_result.hh"
#include "vtb/haptics/local_model.hh"
#include "vtb/linalg/nodal.hh"

#include <vector>

namespace vtb {

/// What the physics publishes for the servo: the deformed body at simulated time t, and per
/// probe the local model of its contact over the next physics step.
template <int dim> struct Snapshot {
  double t = 0;
  bool finite = true;
  Nodal<dim> x, v;
  std::vector<LocalModel<dim>> models; ///< one per probe, sized once
};

/// What the servo sends back for one probe: where its contact acts (no nodes: not touching),
/// the force on the body now, and the forces it applied since it last saw a new snapshot.
template <int dim> struct ContactCommand {
  Footprint footprint;
  Eigen::Matrix<double, dim, 1> force_on_body = Eigen::Matrix<double, dim, 1>::Zero();
  ForceHistory<dim> history;
};
template <int dim> using Commands = std::vector<ContactCommand<dim>>; ///< one per probe, sized once

} // namespace vtb
