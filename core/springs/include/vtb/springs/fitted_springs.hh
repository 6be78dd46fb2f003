#pragma once
/// \file
/// `springs = "fitted"`: spring constants identified from the P1 FEM on the same mesh, for the
/// whole network at once (docs/fidelity.md). Lloyd fits each element alone, which is exact only
/// on equilateral triangles; here every spring is chosen so that the network's static answer
/// to a set of training loads matches the FEM's. The training loads are f_m = K_fem phi_m with
/// phi_m the lowest non-rigid modes of the free mesh (K_fem phi = lambda M phi), scaled as
/// FitOptions::weighting says: the FEM's exact answer to f_m is phi_m itself; the pair springs
/// use no scene's own load (the volume networks do: FitOptions::own_load). With
/// x = log(k / k_prior) (the prior: Lloyd or van Gelder, see FitReport),
///   min_x  1/2 sum_m || P (K_s(x)^+ f_m) - phi_m ||^2  +  mu/2 ||x||^2 ,  k >= floor k_prior,
/// P removing rigid motions, K_s the network's stiffness at rest; solved by Levenberg-Marquardt
/// with a matrix-free CG on the normal equations (each product: one batched solve with the
/// factor of K_s), so that memory stays linear in the mesh.

#include "vtb/meshes/mesh.hh"

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace vtb {

/// Told how a long fit advances: its stage ("modes": the training modes' subspace iteration;
/// "fit": the Levenberg-Marquardt steps; "done" once, at the end), the step and the stage's
/// cap (the fit may stop earlier). For a progress bar; it never changes the fit.
using FitProgress = std::function<void(const char* stage, int step, int steps)>;

/// The training answers' source (FitOptions::target): given the training loads (nodal forces,
/// row dim v + i for node v and component i, one column per load) and the fit's E, nu and
/// thickness, their static answers at the mesh's nodes with the supports held at zero; an
/// empty matrix where it cannot answer (then P1's answers are used). The continuum's
/// (reference_fem's continuum_answers, given by the harness: core does not link deal.II) makes
/// the fit's target the material rather than P1 on the mesh, which locks in bending of thin
/// parts and near incompressibility (docs/fidelity.md).
using TrainingAnswers =
    std::function<Eigen::MatrixXd(const Eigen::MatrixXd& loads, double young_modulus, double nu, double thickness)>;
struct FitTarget {
  TrainingAnswers answers; ///< empty: P1 FEM on the mesh, whose answers are the modes themselves
  /// Names the source in the fit cache's key (empty with P1): fits to different targets are
  /// different constants.
  std::string key;
  /// One line for the run: what the fit was trained on ("the continuum (...)", or why P1).
  std::string how;
  /// The scene's own loads (nodal forces, every load at its full value, one column) and the
  /// target's static answers to them at (E, nu, thickness), the supports held at zero: with
  /// FitOptions::own_load > 0 the fit trains on them beside the modes (docs/volume_term.md).
  /// The answers are asked for only when the fit runs (a cache hit needs the loads alone);
  /// empty loads or answers: none.
  Eigen::MatrixXd own_loads;
  std::function<Eigen::MatrixXd(double young_modulus, double nu, double thickness)> own_answers;
};

struct FitOptions {
  /// Training modes; 0: 16 in 2D, 24 in 3D (with a continuum target, at most the resolved share
  /// below).
  int modes = 0;
  /// With a continuum target and `modes` = 0: at most one training mode per this many free dofs
  /// (and at least kMinModes): the modes a mesh resolves (fitted_springs.cc).
  static constexpr int kResolvedModeShare = 16;
  static constexpr int kMinModes = 6;
  double pull = 1e-2;      ///< mu = pull * mean diag(J^T J) at the start: the weak pull toward the prior
  double floor = 0.01;     ///< k >= floor * k_prior (the prior: Lloyd, at least 1 % of van Gelder, or van Gelder)
  int max_iterations = 40; ///< Levenberg-Marquardt iterations
  /// CG iterations at most per Levenberg-Marquardt step (each: two batched solves). A
  /// truncated inner solve costs no accuracy: on a 1,917-node slab 40 gave the residual of
  /// 200 (7.44e-4 against 7.47e-4) in 26 s instead of 63 s.
  int cg_iterations = 40;
  /// Stop at the second accepted step in a row that lowers the objective by less than this
  /// (relative). One such step is not a plateau: after a rejected step the damping is large and
  /// the next accepted step short, and stopping there left Cook's membrane at 7.0 % where the
  /// fit run on reaches 2.7 % (at weighting 0.4; docs/fidelity.md).
  double tolerance = 5e-3;
  /// Mode m's target and load are scaled by (lambda_1 / lambda_m)^weighting. At 0.5 (the
  /// default) every training answer holds the same strain energy, lambda_1 (phi_m^T K phi_m =
  /// lambda_m for unit phi_m, up to the mass): the low modes a static answer is mostly made of
  /// and the higher ones that carry a local load's near field count alike per unit energy. At 1
  /// (equal load sizes) the higher modes' answers fall as 1/lambda_m and the fit barely sees
  /// them; at 0 (equal displacement sizes) the higher modes, which a spring network represents
  /// worst, crowd out the low ones (docs/decisions/spring_fit_trains_on_supports_stress_states_equal_energy.md).
  double weighting = 0.5;
  /// With supports that hold the body: the weight of the uniform stress answers in the
  /// training set (the FEM's answers, with the supports, to the boundary tractions of each
  /// uniform stress, as loads of the training modes' size). They are the loads of a tension or
  /// shear test, which a clamped body's low modes barely contain. Chosen from 0, 0.3, 1, 2, 4 on
  /// the reproduction's fidelity cases (docs/decisions/spring_fit_trains_on_supports_stress_states_equal_energy.md).
  /// The free body's modes contain its stretching (weight unused).
  double uniform_stress = 2;
  Eigen::VectorXd
      start; ///< the first iterate (per edge); empty: the prior. The pull and floor stay relative to the prior
  /// Nodes the scene holds (its fixes and drives), sorted: the training modes are then the
  /// supported body's (K_ff phi = lambda M_ff phi), whose low modes and boundary layers are
  /// what a clamped scene's answers are made of. Empty: the free body's modes.
  std::vector<int> supports;
  /// Every `holdout`-th training mode (of modes + modes / (holdout - 1) computed) is held out of
  /// the fit and answers the validation: the fit returns whichever of itself, Lloyd and van
  /// Gelder answers the held-out modes best. 0: nothing held out (the fit is returned).
  int holdout = 5;
  /// Early stopping on the held-out modes: with patience > 0 the fit stops at the
  /// `patience`-th accepted step that lowered neither the held-out error (while below the
  /// prior's) nor the objective by `min_improvement` (relative), and keeps its best-held-out
  /// iterate. On small meshes the held-out modes are poorly represented, their error is noisy
  /// and stops the fit early: Cook's membrane (578 dofs) on its clamp reaches 5.1 % with
  /// patience 2 (13 % with the held-out test alone) where the fit to tolerance reaches 3.1 %
  /// (docs/fidelity.md). 0: stop on `tolerance`. kAutoPatience (the default): 1 on meshes of
  /// more than kEarlyStopDofs free dofs, where a step costs several seconds (10 s at 10k nodes
  /// in 3D), else 0. The early stop ends a fit before its constants settle, and two meshes of
  /// one body, one stopped and one run to tolerance, answer a local load differently: an
  /// ellipsoid meshed uniformly (2,540 nodes, 7,620 dofs) stopped after 5 steps at 9.7 %
  /// held-out error and answered a disc load 6.5 % stiffer than its mesh graded toward the
  /// disc (1,099 nodes) did; run to tolerance (25 steps, 7.9 %) 0.4 %. So the threshold sits
  /// above the own bodies a haptic scene presses (up to 5,000 nodes in 3D; docs/meshes.md).
  int patience = kAutoPatience;
  static constexpr int kAutoPatience = -1;
  static constexpr int kEarlyStopDofs = 15000;
  /// The patience a fit of `free_dofs` unknowns runs with.
  int patience_for(int free_dofs) const {
    return patience != kAutoPatience ? patience : free_dofs > kEarlyStopDofs ? 1 : 0;
  }
  double min_improvement = 0.15;
  FitProgress progress; ///< empty: nothing is told (not part of the fit's result or cache key)
  /// With supports that hold the body: the training answers' source (empty: P1 on the mesh).
  FitTarget target;
  /// With a volume term per cell (`springs = "fitted-volume"`, docs/volume_term.md): the
  /// springs and the cells' k_c identified together, x = log(k / k_prior) over both, the prior
  /// the element fit's (lloyd_volume_stiffness, each cell at least 1 % of its bulk modulus
  /// times its volume); the guard weighs the fit against that prior alone.
  bool volume = false;
  /// With the volume term, the fraction of the shear modulus each cell carries in the stable
  /// energy's shear part (`springs = "fitted-stable"`, cell_volumes.hh; 0: none). Fixed, not
  /// fitted: it enters the fit's stiffness as a constant background, the springs and the
  /// cells' k_c identified around it (their prior: the springs' element fit times 1 - fraction,
  /// the cells' plus fraction mu V, which the shear part's rest pull takes off the volume).
  double cell_shear = 0;
  /// With the volume term, averaged per node (cell_volumes.hh): one unknown k_n per node
  /// instead of one per cell (the prior: the element fit's cells lumped to their nodes).
  bool nodal = false;
  /// With a continuum target that answers the scene's own loads (FitTarget::own_loads): their
  /// weight in the training set, each answer scaled to the modes' load size times this (as
  /// `uniform_stress`); 0: the scene's loads are not trained on. The volume networks train on
  /// them (kOwnLoadWeight), the pair springs do not (docs/volume_term.md).
  double own_load = 0;
  static constexpr double kOwnLoadWeight = 2;
};

/// Whether a fit (the volume networks' with `volume`) trains on the scene's own loads: where
/// the target is the continuum and answers them.
inline bool trains_on_own_loads(const FitTarget& target, bool volume) {
  return volume && target.answers && target.own_answers && target.own_loads.cols() > 0;
}

struct FitReport {
  int modes = 0, iterations = 0, cg_iterations = 0;
  double lloyd_residual = 0; ///< sqrt(sum_m ||P u_m - phi_m||^2 / modes) with Lloyd's springs
  std::string prior; ///< the start and the pull's centre: "lloyd" or "van-gelder", whichever fits the modes better
  double fitted_residual = 0; ///< the same with the fitted springs
  /// Relative error ||P u_m - phi_m|| / ||phi_m|| over the held-out modes (the validation), per
  /// candidate; NaN when nothing is held out.
  double validation_lloyd = 0, validation_van_gelder = 0, validation_fitted = 0;
  /// The constants returned: "fitted", or "lloyd" / "van-gelder" when a prior answers the
  /// held-out modes better than the fit (the guard: never worse than the better prior). With
  /// FitOptions::volume the prior is the element fit with its volume term: prior and chosen
  /// are then "volume", its residual and validation in the *_lloyd fields.
  std::string chosen = "fitted";
  double validation() const; ///< the chosen constants' validation error
};

/// The fitted spring constants, per edge of unique_edges(mesh) (plane stress with thickness
/// in 2D). Deterministic: the same mesh and material give the same constants bit for bit.
/// With options.volume the cells' k_c go to *cell_stiffness (required then), in the order
/// make_cell_volumes gives the mesh's cells (cell_volumes.hh).
template <int dim>
Eigen::VectorXd fitted_stiffness(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio, double thickness,
                                 const FitOptions& options = {}, FitReport* report = nullptr,
                                 Eigen::VectorXd* cell_stiffness = nullptr);

/// Whether holding the nodes `supports` removes every rigid motion of the mesh (the rigid
/// modes restricted to their dofs have full column rank). Where they do, the fit trains on
/// the supported body's modes; otherwise on the free body's.
template <int dim> bool supports_hold(const Mesh<dim>& mesh, const std::vector<int>& supports);

/// Free dofs the fit needs beyond its pins (modes, held-out modes and the subspace's margin),
/// and the fit's pinned dofs with these supports; the fit refuses a mesh with fewer.
template <int dim> int fit_dofs_needed(const FitOptions& options = {});
template <int dim> int fit_pinned_dofs(const Mesh<dim>& mesh, const std::vector<int>& supports);

/// Whether `springs = "auto"` fits this mesh: empty if so, else why not (one phrase). Its
/// budget is a node count, not a clock, so that a scene gets the same springs on any machine:
/// 3D meshes up to kAutoFitNodes3D nodes (an organ-size body: a 50k-node fit takes 5-6 min
/// and 1.3-1.6 GB, docs/fidelity.md's cost ladder, once per mesh and cached), 2D up to
/// kAutoFitNodes2D, and meshes large enough to fit.
inline constexpr int kAutoFitNodes2D = 20000, kAutoFitNodes3D = 50000;
template <int dim> std::string fit_affordable(const Mesh<dim>& mesh, const std::vector<int>& supports);

} // namespace vtb
