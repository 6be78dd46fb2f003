// The volume term per cell: its rest data, forces, energy and the volume ratios a run reports.
#include "vtb/springs/cell_volumes.hh"

#include "vtb/base/input_error.hh"
#include "vtb/linalg/vector_clones.hh"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace vtb {

namespace {

/// Cells per chunk of the force pass: its scratch (3 dim^2 doubles a cell) stays in L1 and on
/// the stack, so the step allocates nothing.
constexpr int kCellChunk = 64;

/// The force pass's arithmetic on a chunk of n cells in structure-of-arrays form (component i
/// of edge k of cell c at e[(k dim + i) kCellChunk + c]): from the edge vectors e_k = x_{k+1} -
/// x_0 and the velocity differences w_k = v_{k+1} - v_0, the scaled gradients G_a = s dJ/dx_a
/// (a = 1..dim, out in the same layout) with s = k_c (J - 1) - shift_c + (c_c + extra k_c) dJ/dt
/// (shift_c: the shear part's m_c, which moves the volume's rest to alpha_c; zero without it; the
/// dashpot times volume_dashpot_cap of |cof(D_m)|^2 `rest_norm2` and |cof(D_s)|^2) and
/// dJ/dx_a the columns of cof(D_s) / det(D_m) (volume_ratio_gradients' expressions); averaged
/// per node, s is the cell's given `pressure` (chunk_pressures). No gather: the loop
/// vectorises.
VTB_VECTOR_CLONES void cell_coefficients_3d(int n, const double* __restrict e, const double* __restrict w,
                                            const double* __restrict inverse_rest_det, const double* __restrict k,
                                            const double* __restrict damping, const double* __restrict shift,
                                            const double* __restrict rest_norm2, double extra,
                                            const double* __restrict pressure, double* __restrict G) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double ax = e[0 * C + c], ay = e[1 * C + c], az = e[2 * C + c];
    const double bx = e[3 * C + c], by = e[4 * C + c], bz = e[5 * C + c];
    const double dx = e[6 * C + c], dy = e[7 * C + c], dz = e[8 * C + c];
    const double g1x = by * dz - bz * dy, g1y = bz * dx - bx * dz, g1z = bx * dy - by * dx; // e_1 x e_2
    const double g2x = dy * az - dz * ay, g2y = dz * ax - dx * az, g2z = dx * ay - dy * ax; // e_2 x e_0
    const double g3x = ay * bz - az * by, g3y = az * bx - ax * bz, g3z = ax * by - ay * bx; // e_0 x e_1
    const double inv = inverse_rest_det[c];
    const double J = (ax * g1x + ay * g1y + az * g1z) * inv;
    const double rate =
        (g1x * w[0 * C + c] + g1y * w[1 * C + c] + g1z * w[2 * C + c] + g2x * w[3 * C + c] + g2y * w[4 * C + c] +
         g2z * w[5 * C + c] + g3x * w[6 * C + c] + g3y * w[7 * C + c] + g3z * w[8 * C + c]) *
        inv;
    const double norm2 =
        g1x * g1x + g1y * g1y + g1z * g1z + g2x * g2x + g2y * g2y + g2z * g2z + g3x * g3x + g3y * g3y + g3z * g3z;
    const double cap = volume_dashpot_cap(rest_norm2[c], norm2);
    const double s =
        (pressure ? pressure[c] : k[c] * (J - 1.0) - shift[c] + (damping[c] + extra * k[c]) * cap * rate) * inv;
    G[0 * C + c] = s * g1x, G[1 * C + c] = s * g1y, G[2 * C + c] = s * g1z;
    G[3 * C + c] = s * g2x, G[4 * C + c] = s * g2y, G[5 * C + c] = s * g2z;
    G[6 * C + c] = s * g3x, G[7 * C + c] = s * g3y, G[8 * C + c] = s * g3z;
  }
}

VTB_VECTOR_CLONES void cell_coefficients_2d(int n, const double* __restrict e, const double* __restrict w,
                                            const double* __restrict inverse_rest_det, const double* __restrict k,
                                            const double* __restrict damping, const double* __restrict shift,
                                            const double* __restrict rest_norm2, double extra,
                                            const double* __restrict pressure, double* __restrict G) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double ax = e[0 * C + c], ay = e[1 * C + c], bx = e[2 * C + c], by = e[3 * C + c];
    const double g1x = by, g1y = -bx, g2x = -ay, g2y = ax; // cof(D_s)'s columns
    const double inv = inverse_rest_det[c];
    const double J = (ax * by - bx * ay) * inv;
    const double rate = (g1x * w[0 * C + c] + g1y * w[1 * C + c] + g2x * w[2 * C + c] + g2y * w[3 * C + c]) * inv;
    const double cap = volume_dashpot_cap(rest_norm2[c], ax * ax + ay * ay + bx * bx + by * by);
    const double s =
        (pressure ? pressure[c] : k[c] * (J - 1.0) - shift[c] + (damping[c] + extra * k[c]) * cap * rate) * inv;
    G[0 * C + c] = s * g1x, G[1 * C + c] = s * g1y;
    G[2 * C + c] = s * g2x, G[3 * C + c] = s * g2y;
  }
}

/// The volume ratios J_c of a chunk of n cells (cell_coefficients_3d's layout and expressions)
/// into J and, with velocity differences w (else none), their dashpot-capped rates into rate.
VTB_VECTOR_CLONES void cell_ratios_3d(int n, const double* __restrict e, const double* __restrict w,
                                      const double* __restrict inverse_rest_det, const double* __restrict rest_norm2,
                                      double* __restrict J, double* __restrict rate) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double ax = e[0 * C + c], ay = e[1 * C + c], az = e[2 * C + c];
    const double bx = e[3 * C + c], by = e[4 * C + c], bz = e[5 * C + c];
    const double dx = e[6 * C + c], dy = e[7 * C + c], dz = e[8 * C + c];
    const double g1x = by * dz - bz * dy, g1y = bz * dx - bx * dz, g1z = bx * dy - by * dx;
    J[c] = (ax * g1x + ay * g1y + az * g1z) * inverse_rest_det[c];
    if (!w) continue; // the same branch for every cell: the compiler unswitches it
    const double g2x = dy * az - dz * ay, g2y = dz * ax - dx * az, g2z = dx * ay - dy * ax;
    const double g3x = ay * bz - az * by, g3y = az * bx - ax * bz, g3z = ax * by - ay * bx;
    const double r =
        (g1x * w[0 * C + c] + g1y * w[1 * C + c] + g1z * w[2 * C + c] + g2x * w[3 * C + c] + g2y * w[4 * C + c] +
         g2z * w[5 * C + c] + g3x * w[6 * C + c] + g3y * w[7 * C + c] + g3z * w[8 * C + c]) *
        inverse_rest_det[c];
    const double norm2 =
        g1x * g1x + g1y * g1y + g1z * g1z + g2x * g2x + g2y * g2y + g2z * g2z + g3x * g3x + g3y * g3y + g3z * g3z;
    rate[c] = volume_dashpot_cap(rest_norm2[c], norm2) * r;
  }
}

VTB_VECTOR_CLONES void cell_ratios_2d(int n, const double* __restrict e, const double* __restrict w,
                                      const double* __restrict inverse_rest_det, const double* __restrict rest_norm2,
                                      double* __restrict J, double* __restrict rate) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double ax = e[0 * C + c], ay = e[1 * C + c], bx = e[2 * C + c], by = e[3 * C + c];
    J[c] = (ax * by - bx * ay) * inverse_rest_det[c];
    if (!w) continue;
    const double r =
        (by * w[0 * C + c] - bx * w[1 * C + c] - ay * w[2 * C + c] + ax * w[3 * C + c]) * inverse_rest_det[c];
    rate[c] = volume_dashpot_cap(rest_norm2[c], ax * ax + ay * ay + bx * bx + by * by) * r;
  }
}

/// Gathers a chunk of n cells from c0 in the kernels' layout: the edge vectors into e and, with
/// v, the velocity differences into w; node 0's position and velocity once per run of cells
/// that share it (cells in their lowest node's order, that node first).
template <int dim>
void gather_chunk(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>* v, int c0,
                  int n, double* e, double* w) {
  constexpr int C = kCellChunk;
  int first = -1;
  Vec<dim> x0 = Vec<dim>::Zero(), v0 = Vec<dim>::Zero();
  for (int c = 0; c < n; ++c) {
    const auto& cell = cv.cell[static_cast<std::size_t>(c0 + c)];
    if (cell[0] != first) {
      first = cell[0];
      x0 = rest.col(first) + u.col(first);
      if (v) v0 = v->col(first);
    }
    for (int a = 0; a < dim; ++a) {
      const Vec<dim> ea = rest.col(cell[a + 1]) + u.col(cell[a + 1]) - x0;
      for (int i = 0; i < dim; ++i) e[(a * dim + i) * C + c] = ea[i];
      if (!v) continue;
      const Vec<dim> wa = v->col(cell[a + 1]) - v0;
      for (int i = 0; i < dim; ++i) w[(a * dim + i) * C + c] = wa[i];
    }
  }
}

/// The shear part's forces on a chunk of n cells, added to G (the amount taken from f_a, a >= 1):
/// G_a += sum_k (m e_k + c w_k) S_{k a} with S = D_m^-1 D_m^-T (`metric`: its entries' columns at
/// the chunk) and c = tau m + extra m: m (F + tau dF/dt) times the rest gradient b_a.
VTB_VECTOR_CLONES void cell_shear_3d(int n, const double* __restrict e, const double* __restrict w,
                                     const double* __restrict s00, const double* __restrict s11,
                                     const double* __restrict s22, const double* __restrict s01,
                                     const double* __restrict s02, const double* __restrict s12,
                                     const double* __restrict m, const double* __restrict ms, double extra,
                                     double* __restrict G) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double cm = m[c], cd = ms[c] + extra * m[c];
    double p[9]; // column k of m D_s + c W_s: component i at p[3 k + i]
    for (int q = 0; q < 9; ++q) p[q] = cm * e[q * C + c] + cd * w[q * C + c];
    const double S[3][3] = {{s00[c], s01[c], s02[c]}, {s01[c], s11[c], s12[c]}, {s02[c], s12[c], s22[c]}};
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i) G[(3 * a + i) * C + c] += p[i] * S[0][a] + p[3 + i] * S[1][a] + p[6 + i] * S[2][a];
  }
}

VTB_VECTOR_CLONES void cell_shear_2d(int n, const double* __restrict e, const double* __restrict w,
                                     const double* __restrict s00, const double* __restrict s11,
                                     const double* __restrict s01, const double* __restrict m,
                                     const double* __restrict ms, double extra, double* __restrict G) {
  constexpr int C = kCellChunk;
  for (int c = 0; c < n; ++c) {
    const double cm = m[c], cd = ms[c] + extra * m[c];
    double p[4];
    for (int q = 0; q < 4; ++q) p[q] = cm * e[q * C + c] + cd * w[q * C + c];
    const double S[2][2] = {{s00[c], s01[c]}, {s01[c], s11[c]}};
    for (int a = 0; a < 2; ++a)
      for (int i = 0; i < 2; ++i) G[(2 * a + i) * C + c] += p[i] * S[0][a] + p[2 + i] * S[1][a];
  }
}

/// The cells' J_c into cv.cell_ratio and their weighted means J_n into cv.node_ratio; with v,
/// the same of the cells' dashpot-capped rates dJ_c/dt (cv.cell_rate, cv.node_rate). Chunked
/// as the force pass; allocates nothing.
template <int dim>
void nodal_ratios(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>* v) {
  constexpr int C = kCellChunk;
  alignas(64) double e[dim * dim * C], w[dim * dim * C];
  for (int c0 = 0; c0 < cv.size(); c0 += C) {
    const int n = std::min(C, cv.size() - c0);
    gather_chunk<dim>(cv, rest, u, v, c0, n, e, w);
    const double *inv = cv.inverse_rest_det.data() + c0, *r0 = cv.rest_cofactor_norm2.data() + c0;
    double *J = cv.cell_ratio.data() + c0, *rate = cv.cell_rate.data() + c0;
    if constexpr (dim == 3)
      cell_ratios_3d(n, e, v ? w : nullptr, inv, r0, J, rate);
    else
      cell_ratios_2d(n, e, v ? w : nullptr, inv, r0, J, rate);
  }
  cv.node_ratio.setZero();
  if (v) cv.node_rate.setZero();
  for (int c = 0; c < cv.size(); ++c)
    for (int a = 0; a <= dim; ++a) {
      const int node = cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)];
      cv.node_ratio[node] += cv.node_weight(c, a) * cv.cell_ratio[c];
      if (v) cv.node_rate[node] += cv.node_weight(c, a) * cv.cell_rate[c];
    }
}

/// Averaged per node: the nodes' force coefficients P_n = k_n (J_n - 1) + (c_n + extra k_n)
/// dJ_n/dt into cv.node_pressure (once a node, not once a cell that has it).
template <int dim>
void nodal_forces_pressure(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>& v,
                           double extra) {
  nodal_ratios(cv, rest, u, &v);
  cv.node_pressure.array() = cv.node_stiffness.array() * (cv.node_ratio.array() - 1.0) +
                             (cv.node_damping.array() + extra * cv.node_stiffness.array()) * cv.node_rate.array();
}

/// A chunk's cells' whole force coefficients s_c = sum_a w_ca P_n(a) + k'_c (J_c - 1) + (c'_c +
/// extra k'_c) dJ_c/dt - m_c into p (the kernels' `pressure`).
template <int dim> void chunk_pressures(const CellVolumes<dim>& cv, int c0, int n, double extra, double* p) {
  for (int c = c0; c < c0 + n; ++c) {
    double s = (cv.has_shear() ? -cv.shear[c] : 0.0) + cv.own_stiffness[c] * (cv.cell_ratio[c] - 1.0) +
               (cv.own_damping[c] + extra * cv.own_stiffness[c]) * cv.cell_rate[c];
    for (int a = 0; a <= dim; ++a)
      s += cv.node_weight(c, a) * cv.node_pressure[cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)]];
    p[c - c0] = s;
  }
}

} // namespace

template <int dim> void nodal_pressures(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u) {
  nodal_ratios<dim>(cv, rest, u, nullptr);
  cv.node_pressure.array() = cv.node_stiffness.array() * (cv.node_ratio.array() - 1.0); // once a node
  for (int c = 0; c < cv.size(); ++c) {
    double s = cv.own_stiffness[c] * (cv.cell_ratio[c] - 1.0);
    for (int a = 0; a <= dim; ++a)
      s += cv.node_weight(c, a) * cv.node_pressure[cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)]];
    cv.cell_pressure[c] = s;
  }
}

template <int dim>
void add_volume_forces(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u, const Nodal<dim>& v,
                       Nodal<dim>& f, double extra_damping_per_k) {
  constexpr int C = kCellChunk;
  alignas(64) double e[dim * dim * C], w[dim * dim * C], G[dim * dim * C];
  alignas(64) const double no_shift[C] = {};
  alignas(64) double chunk_pressure[C];
  if (cv.nodal()) nodal_forces_pressure(cv, rest, u, v, extra_damping_per_k);
  const double* pressure = cv.nodal() ? chunk_pressure : nullptr;
  for (int c0 = 0; c0 < cv.size(); c0 += C) {
    const int n = std::min(C, cv.size() - c0);
    gather_chunk<dim>(cv, rest, u, &v, c0, n, e, w);
    if (pressure) chunk_pressures(cv, c0, n, extra_damping_per_k, chunk_pressure);
    const double *inv = cv.inverse_rest_det.data() + c0, *k = cv.stiffness.data() + c0, *d = cv.damping.data() + c0,
                 *r0 = cv.rest_cofactor_norm2.data() + c0;
    // With a shear part the volume pulls toward alpha_c = 1 + m_c / k_c: k_c (J - alpha_c) =
    // k_c (J - 1) - m_c (at rest its pull -m_c dJ/dx_a cancels the shear's m_c b_a).
    const double* shift = cv.has_shear() ? cv.shear.data() + c0 : no_shift;
    if constexpr (dim == 3)
      cell_coefficients_3d(n, e, w, inv, k, d, shift, r0, extra_damping_per_k, pressure, G);
    else
      cell_coefficients_2d(n, e, w, inv, k, d, shift, r0, extra_damping_per_k, pressure, G);
    if (cv.has_shear()) {
      const double *m = cv.shear.data() + c0, *ms = cv.shear_damping.data() + c0;
      const auto col = [&](int q) { return cv.shear_metric.col(q).data() + c0; };
      if constexpr (dim == 3)
        cell_shear_3d(n, e, w, col(0), col(1), col(2), col(3), col(4), col(5), m, ms, extra_damping_per_k, G);
      else
        cell_shear_2d(n, e, w, col(0), col(1), col(2), m, ms, extra_damping_per_k, G);
    }
    // Scatter: f_a -= G_a, f_0 += their sum (sum_a dJ/dx_a = 0), node 0's summed over its run.
    Vec<dim> sum = Vec<dim>::Zero();
    int first = cv.cell[static_cast<std::size_t>(c0)][0];
    for (int c = 0; c < n; ++c) {
      const auto& cell = cv.cell[static_cast<std::size_t>(c0 + c)];
      if (cell[0] != first) {
        f.col(first) += sum;
        first = cell[0];
        sum.setZero();
      }
      for (int a = 0; a < dim; ++a) {
        Vec<dim> Ga;
        for (int i = 0; i < dim; ++i) Ga[i] = G[(a * dim + i) * C + c];
        f.col(cell[a + 1]) -= Ga;
        sum += Ga;
      }
    }
    f.col(first) += sum;
  }
}

template <int dim> double volume_energy(const CellVolumes<dim>& cv, const Nodal<dim>& rest, const Nodal<dim>& u) {
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  double e = 0;
  if (cv.nodal()) {
    nodal_ratios<dim>(cv, rest, u, nullptr);
    e += 0.5 * cv.node_stiffness.dot((cv.node_ratio.array() - 1.0).square().matrix());
  }
  for (int c = 0; c < cv.size(); ++c) {
    const Mat<dim> Ds = edge_matrix<dim>(cv.cell[static_cast<std::size_t>(c)], x);
    const double J = Ds.determinant() * cv.inverse_rest_det[c];
    e += 0.5 * (cv.nodal() ? cv.own_stiffness[c] : cv.stiffness[c]) * (J - 1.0) * (J - 1.0);
    if (cv.has_shear()) {
      const Mat<dim> F = Ds * cv.rest_inverse[static_cast<std::size_t>(c)];
      e += cv.shear[c] * (0.5 * (F.squaredNorm() - dim) - (J - 1.0));
    }
  }
  return e;
}

template <int dim>
VolumeRatios volume_ratios(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                           const Nodal<dim>& u) {
  const auto X = [&](int i) -> Vec<dim> { return rest.col(i); };
  const auto x = [&](int i) -> Vec<dim> { return rest.col(i) + u.col(i); };
  VolumeRatios r;
  for (const auto& cell : cells) {
    const double J = edge_matrix<dim>(cell, x).determinant() / edge_matrix<dim>(cell, X).determinant();
    if (!(J > 0)) ++r.inverted; // NaN counts as inverted
    if (!(J >= r.min_ratio)) r.min_ratio = J;
  }
  return r;
}

template <int dim>
CellVolumes<dim> make_cell_volumes(const std::vector<std::array<int, dim + 1>>& cells, const Nodal<dim>& rest,
                                   Eigen::VectorXd stiffness, double retardation_time) {
  CellVolumes<dim> cv;
  // In the order of their lowest node (the springs run in their first node's order): the force
  // pass then walks the nodes' columns nearly in order instead of a mesher's cell order.
  std::vector<std::size_t> order(cells.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto low = [&](std::size_t c) { return *std::min_element(cells[c].begin(), cells[c].end()); };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return low(a) < low(b); });
  Eigen::VectorXd sorted(stiffness.size());
  for (std::size_t c = 0; c < order.size(); ++c) {
    // Its lowest node first (any order of a cell's nodes gives the same J, its rest data
    // computed from the same order below): the force pass gathers and sums node 0 once per run
    // of cells that share it.
    std::array<int, dim + 1> cell = cells[order[c]];
    std::iter_swap(cell.begin(), std::min_element(cell.begin(), cell.end()));
    cv.cell.push_back(cell);
    sorted[static_cast<Eigen::Index>(c)] = stiffness[static_cast<Eigen::Index>(order[c])];
  }
  stiffness = std::move(sorted);
  cv.rest_inverse.resize(cells.size());
  cv.inverse_rest_det.resize(static_cast<Eigen::Index>(cells.size()));
  cv.rest_cofactor_norm2.resize(static_cast<Eigen::Index>(cells.size()));
  const auto X = [&](int i) -> Vec<dim> { return rest.col(i); };
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const Mat<dim> Dm = edge_matrix<dim>(cv.cell[c], X);
    if (!(std::abs(Dm.determinant()) > 0))
      throw InputError("cell " + std::to_string(order[c]) + ": zero volume, the volume term needs a rest shape");
    cv.rest_inverse[c] = Dm.inverse();
    cv.inverse_rest_det[static_cast<Eigen::Index>(c)] = 1.0 / Dm.determinant();
    Eigen::Matrix<double, dim, dim + 1> g;
    volume_ratio_gradients<dim>(Dm, 1.0, g); // columns 1..dim: cof(D_m)'s
    cv.rest_cofactor_norm2[static_cast<Eigen::Index>(c)] = g.template rightCols<dim>().squaredNorm();
  }
  cv.damping = retardation_time * stiffness;
  cv.stiffness = std::move(stiffness);
  return cv;
}

template <int dim>
void make_nodal_volumes(CellVolumes<dim>& cv, int num_nodes, const Eigen::VectorXd* own,
                        const Eigen::VectorXd* node_stiffness, double retardation_time) {
  const Eigen::Index nc = cv.size();
  cv.own_stiffness = own ? *own : Eigen::VectorXd::Zero(nc);
  cv.own_damping.resize(nc);
  for (Eigen::Index c = 0; c < nc; ++c)
    cv.own_damping[c] = cv.stiffness[c] > 0 ? cv.own_stiffness[c] * cv.damping[c] / cv.stiffness[c] : 0.0;
  Eigen::VectorXd node_volume = Eigen::VectorXd::Zero(num_nodes);
  cv.node_stiffness = Eigen::VectorXd::Zero(num_nodes);
  cv.node_damping = Eigen::VectorXd::Zero(num_nodes);
  cv.node_cells_start.assign(static_cast<std::size_t>(num_nodes) + 1, 0);
  const auto volume = [&](Eigen::Index c) { return 1.0 / std::abs(cv.inverse_rest_det[c]); }; // dim! V_c
  for (Eigen::Index c = 0; c < nc; ++c)
    for (int n : cv.cell[static_cast<std::size_t>(c)]) {
      node_volume[n] += volume(c) / (dim + 1);
      cv.node_stiffness[n] += (cv.stiffness[c] - cv.own_stiffness[c]) / (dim + 1);
      cv.node_damping[n] += (cv.damping[c] - cv.own_damping[c]) / (dim + 1);
      ++cv.node_cells_start[static_cast<std::size_t>(n) + 1];
    }
  for (int n = 0; n < num_nodes; ++n)
    cv.node_cells_start[static_cast<std::size_t>(n) + 1] += cv.node_cells_start[static_cast<std::size_t>(n)];
  cv.node_cells.resize(static_cast<std::size_t>(cv.node_cells_start.back()));
  std::vector<int> fill(cv.node_cells_start.begin(), cv.node_cells_start.end() - 1);
  cv.node_weight.resize(nc, dim + 1);
  for (Eigen::Index c = 0; c < nc; ++c)
    for (int a = 0; a <= dim; ++a) {
      const int n = cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)];
      cv.node_cells[static_cast<std::size_t>(fill[static_cast<std::size_t>(n)]++)] = static_cast<int>(c);
      cv.node_weight(c, a) = volume(c) / (dim + 1) / node_volume[n];
    }
  // The stars: each node's cells' nodes, each once, in the order the cells list them.
  cv.node_star_start.assign(1, 0);
  cv.node_star.clear();
  for (int n = 0; n < num_nodes; ++n) {
    const auto first = static_cast<std::ptrdiff_t>(cv.node_star.size());
    for (int q = cv.node_cells_start[static_cast<std::size_t>(n)];
         q < cv.node_cells_start[static_cast<std::size_t>(n) + 1]; ++q)
      for (int node : cv.cell[static_cast<std::size_t>(cv.node_cells[static_cast<std::size_t>(q)])])
        if (std::find(cv.node_star.begin() + first, cv.node_star.end(), node) == cv.node_star.end())
          cv.node_star.push_back(node);
    cv.node_star_start.push_back(static_cast<int>(cv.node_star.size()));
  }
  cv.cell_ratio.resize(nc);
  cv.cell_rate.resize(nc);
  cv.cell_pressure.resize(nc);
  cv.node_ratio.resize(num_nodes);
  cv.node_rate.resize(num_nodes);
  cv.node_pressure.resize(num_nodes);
  if (node_stiffness) {
    set_node_stiffness(cv, *node_stiffness, retardation_time);
    return;
  }
  for (Eigen::Index c = 0; c < nc; ++c) { // the cells' bounds of the lumped constants
    double k = 0, d = 0;
    for (int a = 0; a <= dim; ++a) {
      const int n = cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)];
      k += cv.node_weight(c, a) * cv.node_stiffness[n];
      d += cv.node_weight(c, a) * cv.node_damping[n];
    }
    cv.stiffness[c] = cv.own_stiffness[c] + k;
    cv.damping[c] = cv.own_damping[c] + d;
  }
}

template <int dim>
void set_node_stiffness(CellVolumes<dim>& cv, const Eigen::VectorXd& node_stiffness, double retardation_time) {
  cv.node_stiffness = node_stiffness;
  cv.node_damping = retardation_time * node_stiffness;
  for (int c = 0; c < cv.size(); ++c) {
    double k = 0;
    for (int a = 0; a <= dim; ++a)
      k += cv.node_weight(c, a) * node_stiffness[cv.cell[static_cast<std::size_t>(c)][static_cast<std::size_t>(a)]];
    cv.stiffness[c] = cv.own_stiffness[c] + k;
  }
  cv.own_damping = retardation_time * cv.own_stiffness;
  cv.damping = retardation_time * cv.stiffness;
}

template <int dim> Eigen::VectorXd modulus_times_volume(const CellVolumes<dim>& cv, double modulus, double thickness) {
  Eigen::VectorXd out(cv.size());
  for (Eigen::Index c = 0; c < out.size(); ++c) // |det D_m| / dim!
    out[c] =
        modulus * (1.0 / (std::abs(cv.inverse_rest_det[c]) * (dim == 2 ? 2.0 : 6.0))) * (dim == 2 ? thickness : 1.0);
  return out;
}

template <int dim>
void set_cell_shear(CellVolumes<dim>& cv, double shear_modulus, double fraction, double thickness,
                    double retardation_time) {
  const auto n = static_cast<Eigen::Index>(cv.size());
  cv.shear = modulus_times_volume(cv, fraction * shear_modulus, thickness);
  cv.shear_metric.resize(n, dim == 3 ? 6 : 3);
  for (Eigen::Index c = 0; c < n; ++c) {
    const Mat<dim>& Bi = cv.rest_inverse[static_cast<std::size_t>(c)];
    const Mat<dim> S = Bi * Bi.transpose();
    if constexpr (dim == 3)
      cv.shear_metric.row(c) << S(0, 0), S(1, 1), S(2, 2), S(0, 1), S(0, 2), S(1, 2);
    else
      cv.shear_metric.row(c) << S(0, 0), S(1, 1), S(0, 1);
  }
  cv.shear_damping = retardation_time * cv.shear;
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template void add_volume_forces<D>(const CellVolumes<D>&, const Nodal<D>&, const Nodal<D>&, const Nodal<D>&,         \
                                     Nodal<D>&, double);                                                               \
  template double volume_energy<D>(const CellVolumes<D>&, const Nodal<D>&, const Nodal<D>&);                           \
  template VolumeRatios volume_ratios<D>(const std::vector<std::array<int, D + 1>>&, const Nodal<D>&,                  \
                                         const Nodal<D>&);                                                             \
  template CellVolumes<D> make_cell_volumes<D>(const std::vector<std::array<int, D + 1>>&, const Nodal<D>&,            \
                                               Eigen::VectorXd, double);                                               \
  template void set_cell_shear<D>(CellVolumes<D>&, double, double, double, double);                                    \
  template void make_nodal_volumes<D>(CellVolumes<D>&, int, const Eigen::VectorXd*, const Eigen::VectorXd*, double);   \
  template void set_node_stiffness<D>(CellVolumes<D>&, const Eigen::VectorXd&, double);                                \
  template Eigen::VectorXd modulus_times_volume<D>(const CellVolumes<D>&, double, double);                             \
  template void nodal_pressures<D>(const CellVolumes<D>&, const Nodal<D>&, const Nodal<D>&);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

} // namespace vtb
