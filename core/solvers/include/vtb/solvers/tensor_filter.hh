#pragma once
/// \file
/// `[solver] filter = "tensor"`: the filtered step with the full rest Jacobian instead of the
/// paper's isotropic Laplacian, and stiffness warping (Mueller et al. 2002) for rotations.
/// `filter = "tensor-multigrid"` is the same step with H_t^-1 applied by one symmetric block
/// V-cycle instead of H_t's factor (TensorSystem below; block_multigrid.hh): the step with the
/// cycle's extra mass Delta_t >= 0, for 3D meshes whose factor is too large.
///
///   H_t = M (1 + dt gamma) + dt D_0 + dt^2 K_0   (dim n x dim n on the free nodes: the spring
///        Jacobian's blocks k n n^T and c n n^T at rest, from the shared assembly),
///   dv_i = dt R_i [H_t^-1 (R^T F)]_i,
///
/// with F the filtered step's node forces and R_i the rotation of node i's neighbourhood
/// (polar part of sum_j (x_j - x_i)(X_j - X_i)^T over its mesh neighbours). For small
/// rotations it is the linearised backward Euler of implicit_euler.hh with the Jacobian frozen
/// at rest, factorised once: the scalar filter's extra mass dt (tau + dt)(K_L (x) I - K) is
/// gone, and with it the lag of the transient (docs/method.md). Allocates nothing per step.
///
/// What the frozen, warped Jacobian leaves explicit is the difference between each spring's
/// direction now and its rest direction turned by its node's rotation (shear turns springs
/// apart from their node's average rotation). Against the dashpots (c = tau k along the
/// spring) that difference is a transverse force c |dn| per unit velocity, treated explicitly:
/// on the paper's plate (tau = 2 s, strain 0.1) it diverged at dt = 10 ms. So H carries, per
/// spring, beta_s times its transverse stiffness and damping, (dt c + dt^2 k)(I - n n^T), with
/// beta_s = twice the spring's mismatch |n - R n_0| (R: the mean of both ends' rotations), or
/// twice the largest mismatch for every spring once that passes kLocalCoverLimit; refactorised
/// (no allocation) when a spring outgrows its beta or the largest mismatch falls 8x below the
/// largest beta. Small deformations keep beta = 0 and no lag (a fixed beta of 0.05 would
/// quadruple the cantilever's tip error), and springs that do not turn are not damped across.
///
/// Couplings from outside (a user's pull, a tool tip's footprint: coupling_set.hh) are solved
/// implicitly, as the springs are: each unit's c w w^T joins H, H' = H + U C U^T (U: a column
/// w on each axis per unit), applied without refactorising by Woodbury's identity, H'^-1 =
/// H^-1 - Z (C^-1 + U^T Z)^-1 Z^T with Z = H^-1 U (dim solves per unit, made again only when
/// the units' nodes or weights or H's factor change; isotropic, so the rotation R leaves it as
/// it is). Treated explicitly, a pull of 4x
/// the mean spring stiffness at the paper's plate's free corner diverged at dt = 10 ms: in the
/// directions where the node's own springs are weak, H holds little more than its mass.

#include "vtb/solvers/coupling_set.hh"
#include "vtb/springs/model.hh"

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>

#include <array>
#include <memory>
#include <vector>

namespace vtb {

/// How the tensor filter solves with H: its factor (`tensor`) or one block V-cycle B
/// (`tensor-multigrid`: 0 < B <= H^-1, so B^-1 = H + Delta, the step with the extra mass Delta;
/// block_multigrid.hh). Both keep H's values where the cover writes them (values(), offset()).
template <int dim> class TensorSystem {
public:
  virtual ~TensorSystem() = default;
  /// Length of the solve's vector, and the position of dof r (dim a + p) in it: index(dim a)
  /// + p (a node's values consecutive, which the filter's gathers rely on).
  virtual Eigen::Index size() const = 0;
  virtual int index(int r) const = 0;
  /// H's stored values, and the offset of entry (r, c) among them (-1: not stored).
  virtual double* values() = 0;
  virtual std::size_t value_count() const = 0;
  virtual long offset(int r, int c) const = 0;
  /// After values() changed.
  virtual void refresh() = 0;
  /// refresh() in parts, for a bounded step: begin_refresh() after values() changed, then
  /// refresh_part(share) until it returns true, each call doing about `share` of the whole
  /// (at least a little); the system is not solved with in between. By default all at once.
  virtual void begin_refresh() {}
  virtual bool refresh_part(double /*share*/) {
    refresh();
    return true;
  }
  /// A second system holding this one's matrix H (given again for a system that is built
  /// anew), laid out as this one: for the refreshes made while this one serves. The V-cycle's
  /// shares this one's prolongators and values() (block_multigrid.hh: only a refresh reads
  /// them), so values() are written only for the refresh that follows, and read back only
  /// after it.
  virtual std::unique_ptr<TensorSystem> twin(const Eigen::SparseMatrix<double>& H) const = 0;
  /// y <- H^-1 y (the factor) or B y (the V-cycle); y laid out by index().
  virtual void solve(Eigen::Ref<Eigen::VectorXd> y) = 0;
  /// 2D, where the system can (the factor: BlockSolve::solve_turned): y <- H^-1 b with node
  /// node[I]'s values turned into and, where out is given, out of the solve in its sweeps.
  /// False where it cannot (y untouched): the caller turns them in loops of its own.
  virtual bool solve_turned(const double* /*force*/, const double* /*turn*/, const int* /*node*/, const int* /*slot*/,
                            double /*scale*/, double* /*y*/, double* /*out*/) {
    return false;
  }
};

/// H's factor, or (multigrid) one block V-cycle on H with the rigid modes at positions x.
template <int dim>
std::unique_ptr<TensorSystem<dim>> make_warped_system(const Eigen::SparseMatrix<double>& H, const Nodal<dim>& x,
                                                      bool multigrid);

template <int dim> class TensorFilter {
public:
  /// multigrid: solve with one block V-cycle instead of H's factor (large 3D meshes).
  TensorFilter(const Model<dim>& model, double dt, bool multigrid = false);
  /// The coupling units the filter solves implicitly at most; more are applied explicitly.
  static constexpr int kMaxCoupled = CouplingSet<dim>::kMaxUnits;
  /// Beyond this direction mismatch from the reference shape the warped reference Jacobian is
  /// not trusted: the filtered step then relinearises at the current shape (docs/method.md).
  static constexpr double kTrustedMismatch = 0.2;
  /// While the relinearisation started past kTrustedMismatch is under way the H in use serves;
  /// past this mismatch it is finished at once.
  static constexpr double kHardMismatch = 0.3;
  /// Linearises again at displacement u: H_t's Jacobian blocks (K's transverse term clamped at
  /// 0 under compression) and the reference vectors that the rotations and the mismatch are
  /// measured from become those of the shape X + u, refactorised (or the V-cycle refreshed),
  /// with no cover. The filter is then lag-free about that shape as it is about the rest shape
  /// at start (docs/method.md). Allocates nothing; costs one refactorisation: at once, or
  /// (at_once false) spread over the next kRefreshParts steps (advance_refresh), the steps
  /// meanwhile solved with the H in use. Supersedes a refresh under way.
  void relinearize(const Nodal<dim>& u, bool at_once = true);
  /// A refactorisation (a new cover, or a relinearisation) is under way in the second system.
  bool refreshing() const { return m_refreshing; }
  /// And it is a relinearisation.
  bool relinearizing() const { return m_refreshing && m_next_relinearized; }
  /// One part of the refresh under way (none: nothing), at the step's largest mismatch; at its
  /// end the new H takes over. A part is 1 / kRefreshParts of the work, or more where a
  /// relinearisation at that pace would not be done before the mismatch, growing as it did
  /// over the last step, reaches kHardMismatch.
  void advance_refresh(double mismatch = 0);
  /// The rest of the refresh under way, now (counted by refreshes_at_once when more than one
  /// part was left: a step that carried a whole refactorisation).
  void finish_refresh();
  long refreshes_at_once() const { return m_refreshes_at_once; }
  /// How many steps a refactorisation is spread over: each step carries 1 / kRefreshParts of
  /// it, so that no step costs a whole factorisation (docs/method.md).
  static constexpr int kRefreshParts = 16;
  /// How many times relinearize() ran.
  long relinearizations() const { return m_relinearizations; }
  /// H's entry (r, c) on the free dofs (row dim a + p: free node a, axis p) as the system holds
  /// it now, the cover included (for tests).
  double entry(int r, int c) {
    const long off = m_h->offset(r, c) >= 0 ? m_h->offset(r, c) : m_h->offset(c, r);
    return off < 0 ? 0.0 : m_h->values()[off];
  }
  /// How many times H was refactorised (or its V-cycle refreshed) after construction: each
  /// relinearisation and each new cover.
  long refactorizations() const { return m_factor_version; }
  /// The rotations at displacement u and the largest direction mismatch, which it returns; the
  /// cover follows it while it is trusted.
  double prepare(const Nodal<dim>& u);
  /// 2D: prepare(u) where the springs' turns at u are already in turns(), made by the force
  /// pass (add_internal_forces_and_turns), so that the rotations need no pass of their own.
  double prepare_turned(const Nodal<dim>& u);
  /// 2D: where the springs' turns go (per spring p, q and per node their sums).
  SpringTurns turns();
  /// dv (dim x free nodes) = dt R H'^-1 R^T F at the prepared displacement (F: dim x nodes,
  /// including the couplings' forces and their -dt k v term), H' = H_t + U C U^T, the
  /// coupling units' c w w^T (coupling_set.hh; none: an empty set).
  void solve(const Nodal<dim>& force, const CouplingSet<dim>& couplings, double dt, Nodal<dim>& dv);
  /// Unit u's block of U^T H^-1 U (world axes; the other units left out): its weighted position
  /// moves by dt^2 times it per N of force on it in the next step. Zero for a unit not coupled.
  Eigen::Matrix<double, dim, dim> unit_response(int u) const {
    return u >= 0 && u < m_coupled ? m_unit_response[static_cast<std::size_t>(u)]
                                   : Eigen::Matrix<double, dim, dim>::Zero();
  }
  /// Moves dv (solve()'s) toward implicit Euler's step where the filter's matrix departs from
  /// the warped rest Jacobian (a cover is on: its transverse damping lags; or H is solved by
  /// the V-cycle, whose B^-1 = H + Delta carries extra mass): one step of conjugate gradients on
  /// implicit Euler's system A x = b, preconditioned by this filter's own R H'^-1 R^T, from x =
  /// dv. A = M (1 + dt gamma) + the couplings' c - dt D(u) - dt^2 K(u) is the current Jacobian
  /// (K's transverse term clamped at 0 under compression, as implicit Euler's), b = dt (F + dt
  /// K(u) v), both applied spring by spring (no matrix). dv becomes the point of the line dv +
  /// alpha z, z the preconditioned residual, nearest to implicit Euler's step in A's energy
  /// norm: never farther from it than the filter's step. When a correction moves the step by
  /// less than kCorrectionGain of its energy, the next kCorrectionRest calls return at once (a
  /// new cover ends the rest) where the departure is a cover's; under the V-cycle, whose Delta
  /// lags every step alike, every call corrects. `force` is solve()'s F (with the dt k axial
  /// term that is dt K(u) v's axial part), u and v the state it was made at. Allocates nothing.
  void correct(const Nodal<dim>& u, const Nodal<dim>& v, const Nodal<dim>& force, const CouplingSet<dim>& couplings,
               double dt, Nodal<dim>& dv);
  /// correct()'s threshold on its gain (docs/method.md: the measured gains of the cases).
  static constexpr double kCorrectionGain = 0.05;
  /// Steps left uncorrected after a correction below that gain.
  static constexpr int kCorrectionRest = 8;
  /// correct()'s gain above which its conjugate gradients take another step, and how many
  /// steps they take at most (docs/method.md). Measured first gains: the 9,864-node slab at nu
  /// 0.25 under the V-cycle 0.08 (a second step moved its error against CVODE from 0.738 to
  /// 0.747 %), a 517-node plate pulled to strain 0.88 0.04 (at most 0.30), a 2,415-node tissue
  /// block at nu 0.49 under the V-cycle 5.2, the next three 2.2, 2.2 and 1.9 (one step 4.0 %,
  /// three while above 0.1 0.80 %, implicit Euler 0.69 %).
  static constexpr double kCorrectionStepGain = 0.1;
  static constexpr int kCorrectionSteps = 3;
  /// The conjugate-gradient steps correct() took beyond its first, over the run.
  long extra_corrections() const { return m_extra_corrections; }
  /// The rotation of each node's neighbourhood at displacement u (identity at rest).
  void rotations(const Nodal<dim>& u);
  /// Node i's rotation after rotations() (2D: made from its (cos, sin)).
  Mat<dim> rotation(int i) const {
    if constexpr (dim == 2) {
      Mat<2> R;
      R << m_polar(0, i), -m_polar(1, i), m_polar(1, i), m_polar(0, i);
      return R;
    } else {
      return m_rotation[static_cast<std::size_t>(i)];
    }
  }
  /// The largest |n_s - R n0_s| over springs s = (i, j), R the normalised mean of R_i and R_j
  /// (rotations(u) first, with the same u: in 2D it reads that pass's per-spring products).
  double direction_mismatch(const Nodal<dim>& u) const;

private:
  /// m_product = -A p for p = m_iterate (correct()'s A at the state of its last residual
  /// pass: m_spring_d, m_spring_q, m_spring_at); returns p . A p.
  double minus_product(const CouplingSet<dim>& couplings, double dt);
  /// dv = dt R y, y the solve's vector (m_rhs) after the solve.
  void turn_out(double dt, Nodal<dim>& dv) const;
  /// 2D: each node's rotation from the turns' sums.
  void turn_rotations();
  /// 3D: each node's 3 / sum |x_j - x_i|^2 over its neighbours in reference vectors `ref`.
  void scale_neighbourhoods(const Nodal<dim>& ref, std::vector<double>& scale) const;
  /// The mismatch at u after the rotations, and the cover that follows it (prepare's rest).
  double follow(const Nodal<dim>& u);
  /// Sets each spring's beta at displacement u with largest mismatch `mismatch`, and starts
  /// the refactorisation in the second system (at_once: finishes it).
  void cover(const Nodal<dim>& u, double mismatch, bool at_once);
  /// Writes H(beta) into the second system's values from m_base and the transverse blocks
  /// (relinearized: the values relinearize() wrote there stay, with no cover), and starts its
  /// refresh.
  void start_refresh(bool relinearized);
  /// The second system takes over (and with a relinearisation, its reference shape).
  void swap_systems();
  /// The largest mismatch at u; `outgrown` (if given): whether a spring passed its trigger.
  double scan(const Nodal<dim>& u, bool* outgrown) const;
  /// Spring s's mismatch at u.
  double spring_mismatch(int s, const Nodal<dim>& u) const;
  /// Adds spring s at u to `tracker` (its vector now and its rest vector turned by both ends'
  /// rotations); true when it passes `trigger`. Defined in the .cc, where scan inlines it.
  template <class Tracker> bool add_spring(Tracker& tracker, int s, const Nodal<dim>& u, double trigger) const;
  /// Below this largest mismatch no spring is covered.
  static constexpr double kCoverFloor = 2e-3;
  /// Past this largest mismatch every spring gets the largest cover (docs/method.md).
  static constexpr double kLocalCoverLimit = 0.1;

  const Model<dim>& m_model;
  std::unique_ptr<TensorSystem<dim>> m_h;    ///< H's factor or V-cycle, in use
  std::unique_ptr<TensorSystem<dim>> m_next; ///< the same for the refresh under way (same pattern)
  bool m_refreshing = false, m_next_relinearized = false;
  std::vector<int> m_index;              ///< per free dof (dim a + p): its position in the solve's vector
  std::vector<int> m_node_at, m_slot_at; ///< per node position in the solve's vector: the node, its free index
  std::vector<Mat<dim>> m_rotation;      ///< 3D, per node (2D: m_polar)
  Nodal<dim> m_spring_rest;              ///< per spring: its rest vector X_j - X_i (the scan reads it in order)
  Nodal<dim> m_spring_ref;               ///< per spring: its vector in the reference shape (relinearize())
  Nodal<dim> m_adj_rest; ///< 3D, per adjacency entry of node i: X_j - X_i (the rotations read it in order)
  Nodal<dim> m_adj_ref;  ///< 3D, the same in the reference shape
  /// A relinearisation under way: its reference vectors, scales and transverse blocks, which
  /// take over with its system (its H(0) is that system's values).
  Nodal<dim> m_spring_ref_next, m_adj_ref_next;
  std::vector<double> m_adj_scale_next, m_tscale_next;
  Nodal<dim> m_tdir_next;
  std::vector<double> m_adj_scale;       ///< 3D, per node: 3 / sum |X_j - X_i|^2 (A's scale for the polar iteration)
  std::vector<double> m_polar_a;         ///< 3D, per node: its scaled A (9 values), the rotations' scratch
  std::vector<unsigned char> m_polar_ok; ///< 3D, per node: whether the polar iteration converged
  Eigen::Matrix2Xd m_polar;              ///< 2D, per node: (A00 + A11, A10 - A01), then the rotation's (cos, sin)
  /// 2D, per spring (row) at the last rotations(), column by column: d . D and D x d.
  Eigen::Matrix<double, Eigen::Dynamic, 2> m_pq;
  std::vector<double> m_base; ///< H(0)'s stored values
  /// Spring s's transverse blocks at beta = 1, +-T_s = +-(dt c + dt^2 k)(I - n n^T) on its
  /// diagonal and off-diagonal blocks: the values at H's offsets m_toff[k], k in [m_tptr[s],
  /// m_tptr[s + 1]).
  std::vector<int> m_tptr, m_toff;
  /// Per spring: T_s's scale dt c + dt^2 k and its direction n in the reference shape.
  std::vector<double> m_tscale;
  Nodal<dim> m_tdir;
  std::vector<unsigned char>
      m_tcode;                 ///< per stored entry: (block * dim + p) * dim + q, blocks (i,i), (j,j), (i,j), (j,i)
  std::vector<int> m_diag_off; ///< per free dof: its diagonal's offset among H's values
  double m_dt = 0;
  long m_relinearizations = 0;
  long m_refreshes_at_once = 0;
  double m_refresh_done = 0;     ///< the shares of the refresh under way handed out so far
  double m_last_mismatch = 0;    ///< advance_refresh's mismatch of the step before
  std::vector<double> m_trigger; ///< per spring: the sin^2 past which it outgrows its beta
  std::vector<double> m_beta;    ///< per spring: its cover (the last cover()'s)
  // correct()'s scratch: the residual and the iterate by nodes (fixed nodes 0), the
  // preconditioned residual by free nodes, and each spring's block of A as q d d^T + a_t I
  // (its vector d, q and a_t).
  Nodal<dim> m_residual, m_iterate, m_direction, m_spring_d, m_product, m_search;
  long m_extra_corrections = 0;
  Eigen::VectorXd m_spring_q, m_spring_at;
  double m_beta_max = 0;     ///< twice the largest mismatch at the last refill
  bool m_multigrid = false;  ///< H solved by the block V-cycle
  int m_correction_rest = 0; ///< correct() calls left to skip
  Eigen::MatrixXd m_rhs;     ///< one column, laid out as m_h's
  /// Takes the coupling units and makes Z again when their nodes or weights or the factor changed.
  void couple(const CouplingSet<dim>& couplings);
  /// y -= Z C^-1 U^T y: H^-1 r turned into H'^-1 r (y laid out as m_h's).
  void correct_for_couplings(Eigen::MatrixXd& y) const;
  /// U's entry for unit u's node q, world axis p, at the node's axis `axis` in the rotated frame.
  double coupling_entry(int u, int q, int p, int axis) const;
  long m_turns = 0, m_z_turns = -1; ///< rotations() calls, and the one Z was made at
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxCoupled * dim, kMaxCoupled * dim>;
  using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxCoupled * dim, 1>;
  long m_factor_version = 0, m_z_version = -1;
  long m_set_version = -1;                       ///< the units' version Z was made for
  const CouplingSet<dim>* m_set = nullptr;       ///< the units coupled now (slots: free indices)
  int m_coupled = 0;                             ///< how many units are coupled now
  std::array<double, kMaxCoupled> m_coupled_k{}; ///< and their dt^2 k + dt c
  Eigen::MatrixXd m_z;                           ///< m_h's layout x (dim per coupled node): H^-1 U
  Eigen::LDLT<Small> m_capacitance;              ///< C^-1 + U^T Z
  std::array<Eigen::Matrix<double, dim, dim>, kMaxCoupled> m_unit_response{}; ///< U^T Z's diagonal blocks
  mutable SmallVec m_small;
};

/// H_t on the free dofs (row dim a + p: free node a, axis p), both triangles stored, with
/// `transverse` (beta) times the springs' transverse stiffness and damping added.
template <int dim>
Eigen::SparseMatrix<double> tensor_filter_matrix(const Model<dim>& model, double dt, double transverse = 0.0);

} // namespace vtb
