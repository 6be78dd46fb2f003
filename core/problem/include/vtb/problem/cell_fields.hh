#pragma once
/// \file
/// Per-cell fields of a deformed mesh, for the frames vtb writes, the viewer's colours and
/// every solver's max_strain (the springs' own per-cell force is in spring_network.hh).

#include "vtb/linalg/nodal.hh"
#include "vtb/meshes/mesh.hh"

#include <string>
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

/// The largest rotation of a cell (radians, in [0, pi]), max over cells: the angle of R in
/// the polar decomposition F = R U of the P1 interpolant's deformation gradient (2D: the
/// signed angle's magnitude; 3D: atan2 of R's axial vector's length and (tr R - 1) / 2; an
/// inverted cell: the closest proper rotation's). NaN propagates.
template <int dim> double max_rotation(const Mesh<dim>& mesh, const Nodal<dim>& u);

/// The regime in which the linear (small-strain) FEM is a reference for a run that reached
/// `rotation` and `strain` (docs/fem.md derives the limits: rotation <= 0.1 rad, strain <=
/// 0.01, the size at which the kinematics the linear theory drops, theta^2 / 2 and
/// epsilon^2 / 2 relative, reach the reference's own 0.5 % budget). Empty inside it; else
/// one line saying what was exceeded and by how much.
std::string small_strain_regime_note(double rotation, double strain);

/// What `vtb run` says of a run (springs, or the linear FEM) beyond that regime: that it "leaves
/// the small-strain regime", by how much, that the load check (`load_checked`: the run has one)
/// is a linear one, and which reference holds there (the neo-Hookean FEM). Empty inside it.
std::string large_strain_run_note(double rotation, double strain, bool load_checked);

} // namespace vtb
