#pragma once
/// \file
/// The network's volume energy per cell (docs/springs.md, "The volume term"): a Voigt unit on
/// each simplex's volume ratio J = det F (area ratio in 2D), beside the pair springs,
///   E_c = k_c / 2 (J - 1)^2,   f_a = -(k_c (J - 1) + c_c dJ/dt) dJ/dx_a,
/// with k_c = kappa_c V_c (J) and its dashpot c_c = tau k_c. J is a polynomial of the nodes
/// (dJ/dx_a is F's cofactor times a rest gradient), finite through inversion, and the force
/// pushes every cell toward J = 1 whatever the sign of J: a cell pressed through its base is
/// pushed back (a pair of central springs is not: it has no orientation).
/// With a shear part (`springs = "fitted-stable"`) a cell carries Smith, de Goes and Kim's
/// stable neo-Hookean energy in Voigt form instead,
///   E_c = m_c / 2 (|F|^2 - dim) + k_c / 2 (J - alpha_c)^2,   alpha_c = 1 + m_c / k_c,
/// with m_c = mu_c V_c and its dashpot tau m_c on dF/dt: the first term is a set of
/// zero-rest-length springs on the cell's edges (cotangent weights, a constant Hessian
/// m_c (b_a . b_b) I), whose stiffness across a compressed edge stays positive where a
/// rest-length spring's k (1 - L0/L) turns negative; alpha_c keeps the rest state free of force.
/// Averaged per node (`springs = "nodal-volume"`, make_nodal_volumes) the volume energy is
///   E = sum_n k_n / 2 (J_n - 1)^2,   J_n = sum_{c at n} w_cn J_c,   w_cn = V_c / ((dim + 1) V_n),
/// V_n = sum_{c at n} V_c / (dim + 1): one volume constraint per node instead of one per cell
/// (a tetrahedral mesh has five to six cells a node and three dofs), the average nodal pressure
/// of Bonet and Burton 1998, which does not lock as one volume per linear cell does.

#include "vtb/linalg/nodal.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <vector>

namespace vtb {

template <int dim> struct CellVolumes {
  std::vector<std::array<int, dim + 1>> cell; ///< the mesh's simplices
  std::vector<Mat<dim>> rest_inverse;         ///< Dm^{-1}, Dm = [X_1 - X_0, ...] at rest
  Eigen::VectorXd inverse_rest_det;           ///< 1 / det(Dm): the force pass's J and dJ/dx (cell_volumes.cc)
  Eigen::VectorXd stiffness;                  ///< k_c = kappa_c V_c, J
  Eigen::VectorXd damping;                    ///< c_c = tau k_c, J s
  /// |cof(D_m)|^2 (the sum over its columns), the volume dashpot's cap (add_volume_forces).
  Eigen::VectorXd rest_cofactor_norm2;
  Eigen::VectorXd shear;         ///< m_c = mu_c V_c, J (none: size 0)
  Eigen::VectorXd shear_damping; ///< tau m_c, J s (size 0 without shear)
  /// D_m^-1 D_m^-T per cell, its upper triangle's entries (00, 11, 22, 01, 02, 12 in 3D; 00,
  /// 11, 01 in 2D) in columns: f_a = -m_c D_s (D_m^-1 D_m^-T) e_a (a >= 1) is the shear's force.
  Eigen::MatrixXd shear_metric;
  /// Averaged per node (none: size 0): w_ca = V_c / ((dim + 1) V_n) of node a of cell c, in
  /// columns a = 0..dim; then `stiffness` and `damping` hold each cell's bound
  /// kbar_c = sum_a w_ca k_n(a) (below) and the node's constants k_n, c_n = tau k_n are here.
  Eigen::MatrixXd node_weight;
  Eigen::VectorXd node_stiffness, node_damping;
  /// Averaged per node, the part k'_c each cell keeps of its own volume term (k'_c/2 (J_c - 1)^2
  /// and its dashpot, make_nodal_volumes' `own`): with `fitted-nodal`, mu V_c, the mu of Smith
  /// et al.'s lambda + mu, which keeps each cell the right way out inside a star that keeps its
  /// volume and stays bounded as lambda grows (no locking); the lambda part goes to the nodes.
  Eigen::VectorXd own_stiffness, own_damping;
  std::vector<int> node_cells_start, node_cells; ///< the cells at node n: node_cells[start[n], start[n+1])
  /// Node n's star, the nodes of its cells (n included), each once in the order its cells list
  /// them: node_star[star_start[n], star_start[n+1]). The exact Jacobian's, the Jacobian
  /// pattern's and the fit's unit of node n.
  std::vector<int> node_star_start, node_star;
  /// The nodal force pass's scratch (sized by make_nodal_volumes; a network steps in one thread):
  /// per cell J_c, its capped rate and its pressure s_c; per node J_n, its rate and its force
  /// coefficient k_n (J_n - 1) + (c_n + extra k_n) dJ_n/dt.
  mutable Eigen::VectorXd cell_ratio, cell_rate, cell_pressure, node_ratio, node_rate, node_pressure;
  bool empty() const { return cell.empty(); }
  bool nodal() const { return node_weight.size() > 0; }
  bool has_shear() const { return shear.size() > 0; }
  int size() const { return static_cast<int>(cell.size()); }
};

/// A cell's edge matrix [x_1 - x_0, ..., x_dim - x_0] of the positions x(i) of its nodes.
template <int dim, class Position> inline Mat<dim> edge_matrix(const std::array<int, dim + 1>& cell, Position&& x) {
  const Vec<dim> x0 = x(cell[0]);
  Mat<dim> D;
  for (int k = 0; k < dim; ++k) D.col(k) = x(cell[k + 1]) - x0;
  return D;
}

/// A cell's volume ratio J = det(D_s) / det(D_m) (returned) and its gradients dJ/dx_a in the
/// columns a = 0..dim of g. With F = D_s D_m^-1, dJ/dx_a (a >= 1) is column a of cof(F) D_m^-T
/// = cof(D_s) cof(D_m^-1) D_m^-T, that is of cof(D_s) / det(D_m): the cross products of the
/// edge vectors now, polynomial (finite through inversion), no rest matrix.
template <int dim>
inline double volume_ratio_gradients(const Mat<dim>& Ds, double inverse_rest_det,
                                     Eigen::Matrix<double, dim, dim + 1>& g) {
  double det;
  if constexpr (dim == 2) {
    g.col(1) << Ds(1, 1), -Ds(0, 1);
    g.col(2) << -Ds(1, 0), Ds(0, 0);
    det = Ds(0, 0) * Ds(1, 1) - Ds(0, 1) * Ds(1, 0);
  } else {
    g.col(1) = Ds.col(1).cross(Ds.col(2));
    g.col(2) = Ds.col(2).cross(Ds.col(0));
    g.col(3) = Ds.col(0).cross(Ds.col(1));
    det = Ds.col(0).dot(g.col(1));
  }
  g.template rightCols<dim>() *= inverse_rest_det;
  g.col(0) = -g.template rightCols<dim>().rowwise().sum();
  return det * inverse_rest_det;
}

/// The rest gradients b_a of a cell's barycentric functions (columns a = 0..dim; b_a, a >= 1, is
/// row a - 1 of D_m^-1, b_0 = -sum of the others): dJ/dx_a at rest.
template <int dim> inline Eigen::Matrix<double, dim, dim + 1> rest_gradients(const Mat<dim>& rest_inverse) {
  Eigen::Matrix<double, dim, dim + 1> b;
  b.template rightCols<dim>() = rest_inverse.transpose();
  b.col(0) = -b.template rightCols<dim>().rowwise().sum();
  return b;
}

/// d^2 J / dx_a dx_b (a dim x dim block; zero for a = b): in 3D the skew matrix of w = F (b_a x
/// b_b) with H(i, k) = eps_ikm w_m, in 2D eps_ik (b_a x b_b) det-free; b_a the rest gradient
/// of node a's barycentric function (b_0 = -sum of the others).
template <int dim> inline Mat<dim> volume_ratio_hessian(const Mat<dim>& F, const Vec<dim>& ba, const Vec<dim>& bb) {
  Mat<dim> H;
  if constexpr (dim == 2) {
    const double c = ba[0] * bb[1] - ba[1] * bb[0];
    H << 0, c, -c, 0;
  } else {
    const Vec<3> w = F * ba.cross(bb);
    H << 0, w[2], -w[1], -w[2], 0, w[0], w[1], -w[0], 0;
  }
  return H;
}

/// The volume dashpot's factor on c_c: min(1, |g_rest|^2 / |g|^2), g = (dJ/dx_1, ..., dJ/dx_dim).
/// A compressed cell's faces widen (a nearly incompressible cell squeezed to half its height:
/// |g|^2 about twice its rest value), and a dashpot c g g^T stronger than twice the rest one the
/// filtered step holds implicitly flips the velocity's sign every step (the filtered scheme's
/// explicit part; measured: a 12 mm haptic press of a nu 0.45 block swung 0.19 <-> 0.49 N step
/// to step). Capped, the dashpot never damps a cell's volume rate more than at rest (docs/volume_term.md).
inline double volume_dashpot_cap(double rest_norm2, double norm2) {
  return norm2 > rest_norm2 ? rest_norm2 / norm2 : 1.0;
}

/// Averaged per node: J_n at X + u into cv.node_ratio and each cell's elastic pressure
/// s_c = sum_a w_ca k_n(a) (J_n(a) - 1) + k'_c (J_c - 1) into cv.cell_pressure (the scratch; each
/// node's k_n (J_n - 1) formed once, into cv.node_pressure).
/// Allocates nothing.
template <int dim> void nodal_pressures(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u);

/// For each cell and each ordered pair (a, b) of its nodes (a = b included), the blocks
/// K = df_a/dx_b and D = df_a/dv_b of the volume term at displacement u:
///   K = -k_c (g_a g_b^T + (J - 1) d^2J/dx_a dx_b),   D = -c_c g_a g_b^T
/// (the dashpot's dependence on positions omitted, as the springs'; c_c capped as in
/// add_volume_forces), and with a shear part
///   K = -k_c g_a g_b^T - (k_c (J - 1) - m_c) d^2J/dx_a dx_b - m_c (b_a . b_b) I,
///   D = -c_c g_a g_b^T - tau m_c (b_a . b_b) I.
/// With `gauss_newton`, K drops its d^2J term: -k_c g g^T - m_c (b . b) I over the cell is
/// negative semidefinite, as the springs' clamp keeps theirs (implicit Euler factors it). Calls add(c, a, b, K, D) with
/// the cell c and its local node indices a, b (global: cv.cell[c][a]). Allocates nothing.
/// Averaged per node, k_c (J - 1) is the cell's nodal pressure s_c = sum_a w_ca k_n(a) (J_n(a) - 1)
/// and k_c g g^T the bound kbar_c g g^T, which dominates the nodes' sum_n k_n g_n g_n^T
/// (g_n = sum_c w_cn g_c, Jensen): implicit integrators and filters take the bound, which is
/// stiffer and so stable; the exact Jacobian adds for_each_nodal_correction.
template <int dim, class Add>
void for_each_cell_block(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, bool gauss_newton,
                         Add&& add) {
  Eigen::Matrix<double, dim, dim + 1> g;
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  if (cv.nodal() && !gauss_newton) nodal_pressures(cv, rest, u);
  for (int c = 0; c < cv.size(); ++c) {
    const auto& cell = cv.cell[static_cast<std::size_t>(c)];
    const Mat<dim>& Bi = cv.rest_inverse[static_cast<std::size_t>(c)];
    const Mat<dim> Ds = edge_matrix<dim>(cell, x);
    const double J = volume_ratio_gradients<dim>(Ds, cv.inverse_rest_det[c], g);
    const double pressure = cv.nodal() && !gauss_newton ? cv.cell_pressure[c] : cv.stiffness[c] * (J - 1.0);
    const Mat<dim> F = Ds * Bi;
    const Eigen::Matrix<double, dim, dim + 1> b = rest_gradients<dim>(Bi);
    const double k = cv.stiffness[c];
    const double d =
        cv.damping[c] * volume_dashpot_cap(cv.rest_cofactor_norm2[c] * cv.inverse_rest_det[c] * cv.inverse_rest_det[c],
                                           g.template rightCols<dim>().squaredNorm());
    const double m = cv.has_shear() ? cv.shear[c] : 0.0, ms = cv.has_shear() ? cv.shear_damping[c] : 0.0;
    for (int a = 0; a <= dim; ++a)
      for (int bn = 0; bn <= dim; ++bn) {
        const Mat<dim> gg = g.col(a) * g.col(bn).transpose();
        const double bb = b.col(a).dot(b.col(bn));
        Mat<dim> K = -k * gg - m * bb * Mat<dim>::Identity();
        if (!gauss_newton && a != bn) K -= (pressure - m) * volume_ratio_hessian<dim>(F, b.col(a), b.col(bn));
        add(c, a, bn, K, Mat<dim>(-d * gg - ms * bb * Mat<dim>::Identity()));
      }
  }
}

/// Averaged per node: what the exact Jacobian adds to for_each_cell_block's (the bound's)
/// Gauss-Newton blocks, per node n over the pairs (i, j) of its star (cv.node_star):
///   K = -k_n (g_n,i g_n,j^T - sum_{c at n} w_cn g_c,i g_c,j^T),   D the same with c_n,
/// g at X + u. Calls add(i, j, K, D) with global node indices; nothing without nodal averaging.
/// Allocates its star's sums (a Jacobian's assembly, not a step).
template <int dim, class Add>
void for_each_nodal_correction(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, Add&& add) {
  if (!cv.nodal()) return;
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  const int nn = static_cast<int>(cv.node_stiffness.size());
  std::vector<Vec<dim>> gn;
  std::vector<Mat<dim>> pair; // sum_c w_cn g_c,i g_c,j^T over the star's pairs, row-major
  Eigen::Matrix<double, dim, dim + 1> g;
  for (int n = 0; n < nn; ++n) {
    const auto star = cv.node_star.begin() + cv.node_star_start[static_cast<std::size_t>(n)];
    const auto star_end = cv.node_star.begin() + cv.node_star_start[static_cast<std::size_t>(n) + 1];
    const auto s = static_cast<std::size_t>(star_end - star);
    gn.assign(s, Vec<dim>::Zero());
    pair.assign(s * s, Mat<dim>::Zero());
    for (int q = cv.node_cells_start[static_cast<std::size_t>(n)];
         q < cv.node_cells_start[static_cast<std::size_t>(n) + 1]; ++q) {
      const int c = cv.node_cells[static_cast<std::size_t>(q)];
      const auto& cell = cv.cell[static_cast<std::size_t>(c)];
      volume_ratio_gradients<dim>(edge_matrix<dim>(cell, x), cv.inverse_rest_det[c], g);
      int self = 0;
      while (cell[static_cast<std::size_t>(self)] != n) ++self;
      const double w = cv.node_weight(c, self);
      std::array<std::size_t, dim + 1> at;
      for (int a = 0; a <= dim; ++a)
        at[static_cast<std::size_t>(a)] =
            static_cast<std::size_t>(std::find(star, star_end, cell[static_cast<std::size_t>(a)]) - star);
      for (int a = 0; a <= dim; ++a) {
        gn[at[static_cast<std::size_t>(a)]] += w * g.col(a);
        for (int b = 0; b <= dim; ++b)
          pair[at[static_cast<std::size_t>(a)] * s + at[static_cast<std::size_t>(b)]] +=
              w * g.col(a) * g.col(b).transpose();
      }
    }
    const double k = cv.node_stiffness[n], d = cv.node_damping[n];
    for (std::size_t i = 0; i < s; ++i)
      for (std::size_t j = 0; j < s; ++j) {
        const Mat<dim> G = gn[i] * gn[j].transpose() - pair[i * s + j];
        add(star[static_cast<std::ptrdiff_t>(i)], star[static_cast<std::ptrdiff_t>(j)], Mat<dim>(-k * G),
            Mat<dim>(-d * G));
      }
  }
}

/// Adds the volume term's forces at X + u, velocities v to f (not cleared); the dashpot is
/// c_c + extra_damping_per_k k_c (as the springs', the filtered scheme passes dt). Allocates
/// nothing.
template <int dim>
void add_volume_forces(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>& v,
                       Nodal<dim>& f, double extra_damping_per_k);

/// The volume term's elastic energy sum k_c/2 (J - 1)^2, with a shear part
/// + m_c/2 (|F|^2 - dim) - m_c (J - 1) (the stable energy less its constant m_c^2 / 2 k_c).
template <int dim> double volume_energy(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u);

/// What a run reports of the cells' volume ratios at X + u (every cell of `cells`, with or
/// without a volume term): the smallest J and how many cells have J <= 0 (inverted or flat).
struct VolumeRatios {
  double min_ratio = 1.0;
  int inverted = 0;
};
template <int dim>
VolumeRatios volume_ratios(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                           const Nodal<dim>& u);

/// The rest data of the cells (Dm^{-1}; throws InputError naming a degenerate cell) with
/// their constants k_c and c_c = tau k_c.
template <int dim>
CellVolumes<dim> make_cell_volumes(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                                   Eigen::VectorXd stiffness, double retardation_time);

/// Averages the volume term per node (E = sum_n k_n / 2 (J_n - 1)^2, above) but for the part
/// `own` (per cell, none: 0) that each cell keeps (own_stiffness): the weights, the nodes' cells
/// and stars, the force pass's scratch. The nodes' constants are `node_stiffness` (c_n = tau k_n,
/// set_node_stiffness) where given; else each node takes a (dim + 1)-th of the rest of its
/// cells' constants, k_n = sum_{c at n} (k_c - k'_c) / (dim + 1) (c_n likewise), so a
/// homogeneous J has the same energy as per cell. `stiffness` and `damping` become the cells'
/// bounds k'_c + kbar_c. num_nodes: the mesh's.
template <int dim>
void make_nodal_volumes(CellVolumes<dim>& cv, int num_nodes, const Eigen::VectorXd* own = nullptr,
                        const Eigen::VectorXd* node_stiffness = nullptr, double retardation_time = 0.0);

/// Sets a nodal term's constants k_n (the fit's) with their dashpots c_n = tau k_n, and the
/// cells' bounds k'_c + kbar_c, kbar_c = sum_a w_ca k_n(a) (and their dashpots) from them.
template <int dim>
void set_node_stiffness(CellVolumes<dim>& cv, const Eigen::VectorXd& node_stiffness, double retardation_time);

/// modulus |V_c| per cell (times the thickness in 2D): mu V_c, the cells' own part of a nodal
/// term, and set_cell_shear's.
template <int dim> Eigen::VectorXd modulus_times_volume(const CellVolumes<dim>& cv, double modulus, double thickness);

/// Gives every cell the shear part m_c = fraction mu |V_c| (mu = E / 2 (1 + nu); times the
/// thickness in 2D) and its dashpot tau m_c.
template <int dim>
void set_cell_shear(CellVolumes<dim>& cv, double shear_modulus, double fraction, double thickness,
                    double retardation_time);

} // namespace vtb
