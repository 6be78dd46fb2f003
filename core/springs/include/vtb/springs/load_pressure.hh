#pragma once
/// \file
/// How hard a scene's loads press on the body: the nominal pressure under its loads, in units of
/// the material's Young's modulus, which `springs = "auto"` reads to choose the network
/// (docs/volume_term.md, "What auto builds").

#include "vtb/meshes/mesh.hh"

#include <Eigen/Core>

namespace vtb {

/// The pressure, in units of Young's modulus, from which `springs = "auto"` builds the volume
/// network (`fitted-nodal`) instead of the pair springs: under a disc of radius a pressing p on a
/// half-space the centre sinks 2 (1 - nu^2) p a / E, 16-18 % of a at 0.1 E (nu 0.45-0.3), where
/// the pair network leaves the neo-Hookean continuum and begins to invert cells (docs/fem.md's
/// deep press).
inline constexpr double kDeepLoadPressure = 0.1;

/// The largest -f_n . n_n / A_n over the boundary nodes, divided by `young_modulus`: f_n a
/// node's force (entries dim n .. dim n + dim - 1 of `nodal_loads`' first column: every load at
/// its full value), A_n its share of the boundary (a 1/dim part of each boundary facet at it; a
/// facet's length times `thickness` in 2D) and n_n the outward normal of those parts' sum. A
/// uniform traction pressing p on a flat patch gives exactly p at the patch's inner nodes (less
/// at its rim), so a disc or a face pressed whole reads as its pressure; a point load reads as
/// its force over the node's share of the surface, the pressure the mesh spreads it on. A pull
/// or a shear presses nothing; 0 where no boundary node is pressed or `nodal_loads` is empty.
template <int dim>
double deepest_load_pressure(const Mesh<dim>& mesh, const Eigen::MatrixXd& nodal_loads, double young_modulus,
                             double thickness);

} // namespace vtb
