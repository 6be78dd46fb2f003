#pragma once
/// Central differences of a volume term's energy (test_cell_volumes.cc, test_nodal_volumes.cc).
#include "vtb/springs/cell_volumes.hh"

namespace vtb::test {

/// -dE/du by central differences of step h, component by component: the force the term's
/// energy implies at X + u.
template <int dim>
Nodal<dim> minus_energy_gradient(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, double h) {
  Nodal<dim> fd(dim, u.cols());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    Nodal<dim> up = u, um = u;
    up.data()[k] += h;
    um.data()[k] -= h;
    fd.data()[k] = -(volume_energy(cv, rest, up) - volume_energy(cv, rest, um)) / (2 * h);
  }
  return fd;
}

} // namespace vtb::test
