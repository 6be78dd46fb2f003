#pragma once
/// \file
/// The immutable mass-spring model: nodes with lumped masses, one Voigt element per edge.

#include "vtb/meshes/mesh.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/cell_volumes.hh"
#include "vtb/springs/fitted_springs.hh"
#include "vtb/springs/spring_kernels.hh"

#include <limits>
#include <string>
#include <vector>

namespace vtb {

template <int dim> struct SpringNetwork {
  Nodal<dim> rest;                      ///< rest positions X
  Eigen::VectorXd mass;                 ///< lumped nodal masses
  std::vector<std::array<int, 2>> edge; ///< springs (i < j)
  Eigen::VectorXd rest_length;          ///< L0 per spring
  Eigen::VectorXd stiffness;            ///< k per spring, N/m
  Eigen::VectorXd damping;              ///< c = tau k per spring, N s/m
  double mass_damping = 0;              ///< gamma, 1/s: force -gamma m v on every node
  /// The volume term per cell ("volume", "fitted-volume", "fitted-stable"; empty otherwise): every force pass,
  /// Jacobian and integrator takes it beside the springs (cell_volumes.hh).
  CellVolumes<dim> volume;
  std::string calibration; ///< the constants used: "lloyd" | "van-gelder" | "fitted" | "volume" | "fitted-volume" |
                           ///< "fitted-stable"
  std::string calibration_requested; ///< the scene's [solver].springs: the above or "auto"
  double calibration_seconds = 0;    ///< wall time of the stiffness calibration (the fit, for "fitted")
  bool calibration_cached = false;   ///< the fit's constants came from the fit cache (fitted_cache.hh)
  /// The fit trained on the scene's own loads (the volume networks with a continuum target):
  /// calibration_load_error is then measured on a load the fit saw.
  bool calibration_own_loads = false;
  /// When a fit ran (or was read): the used constants' relative error on the fit's held-out
  /// modes (FitReport::validation); NaN otherwise.
  double calibration_validation = std::numeric_limits<double>::quiet_NaN();
  /// The springs' linear static error on the scene's own loads against the yardstick
  /// (static_load_check, load_check.hh; set by build_model): the continuum where it was
  /// solved, else P1 FEM on the mesh. NaN where not measured.
  double calibration_load_error = std::numeric_limits<double>::quiet_NaN();
  /// P1 FEM on the mesh against the continuum on the same check: the mesh's own error (its
  /// locking in bending and near incompressibility). NaN without the continuum.
  double mesh_fem_load_error = std::numeric_limits<double>::quiet_NaN();
  std::string calibration_yardstick;
  /// What a fit was trained on (FitTarget::how): the continuum, or P1 FEM on the mesh; empty
  /// without a fit.
  std::string calibration_target; ///< what calibration_load_error is measured against (LoadCheck::yardstick)
  /// One line when the constants are not what was asked for: auto beyond its budget, or the
  /// fit's guard keeping a prior. Empty otherwise.
  std::string calibration_note;

  /// Adjacency in CSR form: the springs at node i are adj_spring[adj_ptr[i] .. adj_ptr[i+1]),
  /// leading to adj_node[...] (sorted by neighbour).
  std::vector<int> adj_ptr, adj_node, adj_spring;

  int num_nodes() const { return static_cast<int>(mass.size()); }
  int num_springs() const { return static_cast<int>(edge.size()); }
};

/// The fraction of the shear modulus a cell's shear part carries with `springs = "fitted-stable"`
/// (FitOptions::cell_shear; docs/volume_term.md says what it measured).
inline constexpr double kStableCellShear = 0.5;

/// Builds the network of a mesh with the scene's material and calibration ("lloyd",
/// "van-gelder", "fitted", "auto": fitted within auto's budget, fit_affordable, else Lloyd;
/// "volume": Lloyd's element fit with a volume term per cell; "fitted-volume": the springs and
/// that term fitted together; "fitted-stable": the same with the stable energy's shear part,
/// kStableCellShear of the shear modulus, in every cell, cell_volumes.hh).
/// `supports`: the nodes the scene holds (sorted), which the fit trains with; `progress`: told
/// how a fit advances (fitted_springs.hh).
template <int dim>
SpringNetwork<dim> build_network(const Mesh<dim>& mesh, const MaterialDesc& material, std::string_view calibration,
                                 const std::vector<int>& supports = {}, const FitProgress& progress = {},
                                 const FitTarget& target = {});

/// Adds the internal forces at positions X + u and velocities v to f (f is not cleared):
/// Voigt elements with dashpot c + extra_damping_per_k * k (the filtered scheme passes dt
/// for its k dt (v_j - v_i) term), the volume term's (its dashpot likewise), and -gamma m v.
/// Allocates nothing.
template <int dim>
void add_internal_forces(const SpringNetwork<dim>& net, const Nodal<dim>& u, const Nodal<dim>& v, Nodal<dim>& f,
                         double extra_damping_per_k = 0.0);

/// What the 2D tensor filter's rotations read of the springs (tensor_filter.cc), per spring
/// s = (i, j): p = d . D and q = D x d (d = x_j - x_i now, D = X_j - X_i at rest; both the
/// same from either end; p^2 + q^2 = |d|^2 |D|^2, which the scan reads from them instead of a
/// third array, docs/performance.md item 15); per node, (sum p, sum q) over its springs, whose
/// angle is that of the polar factor of its neighbourhood's sum of d D^T.
struct SpringTurns {
  const double* rest;     ///< per spring, given: D (2 values)
  double* p;              ///< per spring
  double* q;              ///< per spring
  Eigen::Matrix2Xd* sums; ///< per node (set, not added to)
};

/// add_internal_forces in 2D, and the springs' turns in the same pass: the tensor filter's
/// rotations then cost no gather and no loop of their own (docs/performance.md item 14).
void add_internal_forces_and_turns(const SpringNetwork<2>& net, const Nodal<2>& u, const Nodal<2>& v, Nodal<2>& f,
                                   double extra_damping_per_k, const SpringTurns& turns);

/// The springs' turns alone (no forces).
void spring_turns(const SpringNetwork<2>& net, const Nodal<2>& u, const SpringTurns& turns);

/// For springs s0 + k, k in [0, n): adds term(k) (a Vec<dim>) to f's column of the spring's
/// first node and kSecond * term(k) to its second node's (-1: a pair of opposite forces, +1: a
/// quantity both ends share). Springs come sorted by their first node (unique_edges), so that
/// node's sum stays in registers over its run and is stored once: adding into f spring by
/// spring made every spring wait on the previous one's store to the same node (1.4x slower on
/// the plate, docs/performance.md). Calls term in spring order.
template <int kSecond, int dim, class Term>
[[gnu::always_inline]] inline void add_by_first_node_runs(const SpringNetwork<dim>& net, int s0, int n,
                                                          Eigen::Matrix<double, dim, Eigen::Dynamic>& f, Term&& term) {
  if (n <= 0) return;
  const auto* e = net.edge.data() + s0;
  int i = e[0][0];
  Vec<dim> sum = Vec<dim>::Zero();
  for (int k = 0; k < n; ++k) {
    if (e[k][0] != i) {
      f.col(i) += sum;
      i = e[k][0];
      sum.setZero();
    }
    const Vec<dim> t = term(k);
    sum += t;
    if constexpr (kSecond < 0)
      f.col(e[k][1]) -= t;
    else
      f.col(e[k][1]) += t;
  }
  f.col(i) += sum;
}

/// Largest |l / L0 - 1| over all springs at X + u.
template <int dim> double max_strain(const SpringNetwork<dim>& net, const Nodal<dim>& u);

/// Elastic energy sum 1/2 k (l - L0)^2 (and the volume term's) and kinetic energy sum 1/2 m |v|^2.
template <int dim> double elastic_energy(const SpringNetwork<dim>& net, const Nodal<dim>& u);
template <int dim> double kinetic_energy(const SpringNetwork<dim>& net, const Nodal<dim>& v);

/// The mean over a cell's edges of its spring's axial force k (l - L0) (N, tension > 0).
template <int dim>
void cell_spring_force(const Mesh<dim>& mesh, const SpringNetwork<dim>& net, const Nodal<dim>& u,
                       std::vector<double>& out);

} // namespace vtb
