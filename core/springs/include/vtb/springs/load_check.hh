#pragma once
/// \file
/// How far the springs are from the continuum on the scene's own loads: every run's check of
/// its calibration (docs/fidelity.md, "Every run measures its springs").

#include "vtb/problem/problem.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/SparseCore>

#include <functional>
#include <limits>
#include <optional>
#include <string>

namespace vtb {

/// Above this many free dofs the check is not made (two sparse factorisations: 1.5-2.4 s and
/// a 412 MB peak at 30k dofs, a 10k-node 3D mesh, growing with the factor's 3D fill; the fit
/// goes further, to kAutoFitNodes3D nodes).
inline constexpr int kLoadCheckDofs = 40000;

/// Issue 25's goal for the default springs, met by the fitted springs on every case of
/// fidelity.csv: `vtb run` says so in a line when a scene's static_load_error is above it.
inline constexpr double kLoadErrorGoal = 0.05;

/// K's rows and columns at the problem's free nodes' dofs, (free node a, component i) ->
/// dim a + i, from K's node-major dofs (node v, component i) -> dim v + i: the system a static
/// answer with the fixed and driven nodes held at zero solves.
template <int dim>
Eigen::SparseMatrix<double> free_dof_block(const Eigen::SparseMatrix<double>& K, const Problem<dim>& problem);

/// The yardstick's answer to the load check's static problem (every load at its full value,
/// fixed and driven nodes at zero) at the mesh's nodes, and one line on how it was obtained:
/// the converged continuum (reference_fem's vtb/fem/continuum.hh supplies it, through the
/// harness: core does not link deal.II).
template <int dim> struct YardstickAnswer {
  Nodal<dim> u;
  std::string how;
};
template <int dim>
using YardstickSolve = std::function<std::optional<YardstickAnswer<dim>>(const Problem<dim>&, const MaterialDesc&)>;
/// The continuum's static solve for each dimension; an empty function or a nullopt answer (the
/// solve beyond its budget) leaves P1 on the mesh as the yardstick.
/// Where a fit's training answers come from on this problem (FitTarget, fitted_springs.hh).
template <int dim> using FitTargetFor = std::function<FitTarget(const Problem<dim>&, const MaterialDesc&)>;
struct Yardstick {
  YardstickSolve<2> plane;
  YardstickSolve<3> solid;
  FitTargetFor<2> plane_target; ///< empty: fits train on P1 on the mesh
  FitTargetFor<3> solid_target;
  template <int dim> const YardstickSolve<dim>& solve() const {
    if constexpr (dim == 2)
      return plane;
    else
      return solid;
  }
  template <int dim> const FitTargetFor<dim>& target() const {
    if constexpr (dim == 2)
      return plane_target;
    else
      return solid_target;
  }
};

/// The load check's numbers: the springs against the yardstick, and P1 on the mesh against it.
struct LoadCheck {
  double springs = std::numeric_limits<double>::quiet_NaN();  ///< the springs' error against the yardstick
  double mesh_fem = std::numeric_limits<double>::quiet_NaN(); ///< P1 on the mesh against the continuum
  std::string yardstick; ///< "the continuum (P2 refined 1x ...)" or "P1 FEM on the mesh"
};

/// The springs' linear static answer to the scene's loads, each at its full value, against the
/// yardstick's with the same nodes held (fixed and driven nodes at zero): the relative L2
/// displacement error over all nodes (fidelity.csv's measure, on this scene). Both answers are
/// linear and static, so the difference is the calibration (and, against P1 on the mesh, its
/// locking is not seen). The yardstick is the continuum where `yardstick` answers, else P1 on
/// the same mesh. NaN where it is not measured: no load (or loads that sum to zero force on
/// every node), held nodes that leave a rigid motion free, or more than kLoadCheckDofs free dofs.
template <int dim>
LoadCheck static_load_check(const Problem<dim>& problem, const SpringNetwork<dim>& net, const MaterialDesc& material,
                            const Yardstick* yardstick = nullptr);

/// static_load_check against P1 on the mesh: the springs' error alone.
template <int dim>
double static_load_error(const Problem<dim>& problem, const SpringNetwork<dim>& net, const MaterialDesc& material) {
  return static_load_check<dim>(problem, net, material).springs;
}

} // namespace vtb
