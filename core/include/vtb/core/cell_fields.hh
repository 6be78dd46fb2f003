#pragma once
/// \file
/// Per-cell fields of a deformed mesh, for the frames vtb writes, the viewer's colours and
/// every solver's max_strain (the springs' own per-cell force is in spring_network.hh).

#include "vtb/core/nodal.hh"
#include "vtb/meshes/mesh.hh"

#include <vector>

namespace vtb {

/// max |eigenvalue| of E = (F^T F - I) / 2, F = Ds Dm^-1 the cell's deformation gradient at
/// displacement u; `out` is resized to the cell count (no allocation once sized). A
/// non-finite cell gives +inf.
template <int dim> void cell_max_principal_strain(const Mesh<dim>& mesh, const Nodal<dim>& u, std::vector<float>& out);

/// The largest principal small strain, max over cells of |eigenvalue| of sym(grad u) of the
/// P1 interpolant of u on the mesh: the definition the FEM's summary uses (at its cells'
/// centres), so that `max_strain` means one thing for every solver.
template <int dim> double max_small_strain(const Mesh<dim>& mesh, const Nodal<dim>& u);

} // namespace vtb
