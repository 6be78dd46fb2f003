#pragma once
/// \file
/// How far the springs are from the continuum on the scene's own loads: every run's check of
/// its calibration (docs/fidelity.md, "Every run measures its springs").

#include "vtb/problem/problem.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/SparseCore>

namespace vtb {

/// Above this many free dofs the check is not made (two sparse factorisations: 1.5-2.4 s and
/// a 412 MB peak at 30k dofs, a 10k-node 3D mesh; the fit's own budget, kAutoFitNodes3D, is
/// 36k dofs).
inline constexpr int kLoadCheckDofs = 40000;

/// Issue 25's goal for the default springs, met by the fitted springs on every case of
/// fidelity.csv: `vtb run` says so in a line when a scene's static_load_error is above it.
inline constexpr double kLoadErrorGoal = 0.05;

/// K's rows and columns at the problem's free nodes' dofs, (free node a, component i) ->
/// dim a + i, from K's node-major dofs (node v, component i) -> dim v + i: the system a static
/// answer with the fixed and driven nodes held at zero solves.
template <int dim>
Eigen::SparseMatrix<double> free_dof_block(const Eigen::SparseMatrix<double>& K, const Problem<dim>& problem);

/// The springs' linear static answer to the scene's loads, each at its full value, against the
/// P1 FEM's on the same mesh with the same nodes held (fixed and driven nodes at zero): the
/// relative L2 displacement error over all nodes (fidelity.csv's measure, on this scene). Both
/// answers are linear and static, so the difference is the calibration alone. NaN where it is
/// not measured: no load (or loads that sum to zero force on every node), held nodes that
/// leave a rigid motion free, or more than kLoadCheckDofs free dofs.
template <int dim>
double static_load_error(const Problem<dim>& problem, const SpringNetwork<dim>& net, const MaterialDesc& material);

} // namespace vtb
