// The stable energy's shear part per cell (cell_volumes.hh, `springs = "fitted-stable"`):
// E_c = m_c/2 (|F|^2 - dim) + k_c/2 (J - alpha_c)^2 with alpha_c = 1 + m_c / k_c. Its force is
// minus its energy's gradient (one cell through inversion, and a box of 432 cells, where the
// force pass runs chunks of 64); the rest state and every rotation of it carry no force; and
// with the whole shear modulus (m_c = mu V, k_c = (lambda + mu) V) its rest stiffness is the
// linear P1 element's, the linearisation of Smith, de Goes and Kim's energy.
//
// Tolerances: the energy is a polynomial of the nodes (degree dim), so central differences with
// step h have truncation error ~ h^2 |E'''| and round-off ~ eps E / h: 1e-7 of the largest force
// bounds both at h = 1e-6 of the cell, where a sign error or a dropped term is O(1) of it. The
// element stiffness and the rotations' zero force are exact but for round-off (1e-12).
#include "vtb/problem/scene.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/cell_volumes.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/model.hh"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace vtb {
namespace {

template <int dim> Mesh<dim> unit_simplex() {
  Mesh<dim> m;
  m.points = Nodal<dim>::Zero(dim, dim + 1);
  for (int k = 0; k < dim; ++k) m.points(k, k + 1) = 1.0;
  typename Mesh<dim>::Cell c;
  for (int a = 0; a <= dim; ++a) c[static_cast<std::size_t>(a)] = a;
  m.cells.push_back(c);
  return m;
}

/// The cells of `m` with k_c = 2 |V_c| and m_c = 0.7 |V_c| (lambda + mu = 2, mu = 0.7), no dashpot.
template <int dim> CellVolumes<dim> stable_cells(const Mesh<dim>& m) {
  CellVolumes<dim> cv = make_cell_volumes<dim>(m.cells, m.points, Eigen::VectorXd::Zero(m.num_cells()), 0.0);
  set_cell_shear(cv, 0.7, 1.0, 1.0, 0.0);
  cv.stiffness = cv.shear * (2.0 / 0.7);
  cv.damping.setZero();
  return cv;
}

template <int dim>
Eigen::VectorXd minus_energy_gradient(const CellVolumes<dim>& cv, const Nodal<dim>& X, const Nodal<dim>& u, double h) {
  Eigen::VectorXd g(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    Nodal<dim> up = u, um = u;
    up.data()[k] += h;
    um.data()[k] -= h;
    g[k] = -(volume_energy(cv, X, up) - volume_energy(cv, X, um)) / (2 * h);
  }
  return g;
}

template <int dim> Eigen::VectorXd forces(const CellVolumes<dim>& cv, const Nodal<dim>& X, const Nodal<dim>& u) {
  Nodal<dim> f = Nodal<dim>::Zero(dim, X.cols());
  const Nodal<dim> v = Nodal<dim>::Zero(dim, X.cols());
  add_volume_forces(cv, X, u, v, f, 0.0);
  return Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
}

template <int dim> void check_one_cell(unsigned seed) {
  const Mesh<dim> m = unit_simplex<dim>();
  const CellVolumes<dim> cv = stable_cells(m);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-0.8, 0.8);
  int inverted = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Nodal<dim> u(dim, dim + 1);
    for (Eigen::Index k = 0; k < u.size(); ++k) u.data()[k] = r(gen);
    inverted += volume_ratios<dim>(m.cells, m.points, u).inverted;
    const Eigen::VectorXd f = forces(cv, m.points, u), fd = minus_energy_gradient(cv, m.points, u, 1e-6);
    EXPECT_LT((f - fd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, f.cwiseAbs().maxCoeff())) << "trial " << trial;
  }
  EXPECT_GT(inverted, 0) << "some trials pass through inversion";
}

TEST(CellShear, ForceIsMinusTheEnergysGradientThroughInversion2D) {
  check_one_cell<2>(5);
}
TEST(CellShear, ForceIsMinusTheEnergysGradientThroughInversion3D) {
  check_one_cell<3>(6);
}

TEST(CellShear, ForceIsMinusTheEnergysGradientOnABoxOfSeveralChunks) {
  const Scene s = parse_scene(R"(
[scene]
duration = 1.0
output_interval = 0.1
[mesh]
generate = { shape = "box", size = [0.06, 0.04, 0.03], divisions = [6, 4, 3] }
[material]
young_modulus = 1.0e4
poisson_ratio = 0.45
density = 1000.0
)",
                              "shear.toml", ".");
  const Mesh<3> mesh = std::get<Mesh<3>>(load_mesh(s));
  ASSERT_GT(mesh.num_cells(), 6 * 64) << "the force pass's chunks of 64 cells, several of them";
  const CellVolumes<3> cv = stable_cells(mesh);
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> r(-1.0, 1.0);
  Nodal<3> u(3, mesh.num_nodes());
  for (Eigen::Index k = 0; k < u.size(); ++k) u.data()[k] = 0.003 * r(gen); // 30 % of a cell
  const Eigen::VectorXd f = forces(cv, mesh.points, u), fd = minus_energy_gradient(cv, mesh.points, u, 1e-8);
  EXPECT_LT((f - fd).cwiseAbs().maxCoeff(), 1e-7 * f.cwiseAbs().maxCoeff());
}

template <int dim> void check_rest_and_rotations() {
  const Mesh<dim> m = unit_simplex<dim>();
  const CellVolumes<dim> cv = stable_cells(m);
  const Nodal<dim> zero = Nodal<dim>::Zero(dim, dim + 1);
  EXPECT_LT(forces(cv, m.points, zero).cwiseAbs().maxCoeff(), 1e-12);
  for (double angle : {0.3, 1.7, 3.0}) {
    Mat<dim> R;
    if constexpr (dim == 2)
      R = Eigen::Rotation2Dd(angle).toRotationMatrix();
    else
      R = Eigen::AngleAxisd(angle, Vec<3>(1, 2, 3).normalized()).toRotationMatrix();
    const Nodal<dim> u = R * m.points - m.points;
    EXPECT_LT(forces(cv, m.points, u).cwiseAbs().maxCoeff(), 1e-12) << "angle " << angle;
  }
}

TEST(CellShear, TheRestStateAndItsRotationsCarryNoForce2D) {
  check_rest_and_rotations<2>();
}
TEST(CellShear, TheRestStateAndItsRotationsCarryNoForce3D) {
  check_rest_and_rotations<3>();
}

/// m_c = mu V, k_c = (lambda + mu) V (plane stress's lambda in 2D): -K at rest is the P1
/// element's stiffness.
template <int dim> void check_linearisation() {
  Mesh<dim> m = unit_simplex<dim>();
  m.points.col(1) << Vec<dim>::Unit(0) * 1.3;
  m.points(0, dim) = 0.4; // a skewed cell
  const double E = 3e3, nu = 0.4, t = 0.002, mu = E / (2 * (1 + nu));
  const double lambda = dim == 2 ? E * nu / (1 - nu * nu) : E * nu / ((1 + nu) * (1 - 2 * nu));
  CellVolumes<dim> cv = make_cell_volumes<dim>(m.cells, m.points, Eigen::VectorXd::Zero(1), 0.0);
  set_cell_shear(cv, mu, 1.0, t, 0.0);
  cv.stiffness = cv.shear * ((lambda + mu) / mu);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(dim * (dim + 1), dim * (dim + 1));
  const Nodal<dim> zero = Nodal<dim>::Zero(dim, dim + 1);
  for_each_cell_block(cv, m.points, zero, false, [&](int c, int a, int b, const Mat<dim>& Kab, const Mat<dim>&) {
    const int i = cv.cell[static_cast<std::size_t>(c)][a];
    const int j = cv.cell[static_cast<std::size_t>(c)][b];
    K.block(dim * i, dim * j, dim, dim) -= Kab;
  });
  const Eigen::MatrixXd fem = fem_element_stiffness(m, m.cells[0], E, nu, t);
  EXPECT_LT((K - fem).cwiseAbs().maxCoeff(), 1e-12 * fem.cwiseAbs().maxCoeff());
}

TEST(CellShear, WithTheWholeShearModulusTheRestStiffnessIsTheP1Elements2D) {
  check_linearisation<2>();
}
TEST(CellShear, WithTheWholeShearModulusTheRestStiffnessIsTheP1Elements3D) {
  check_linearisation<3>();
}

} // namespace
} // namespace vtb

namespace vtb {
namespace {

template <int dim> void check_dashpot_cap() {
  // The volume dashpot c_c g g^T (g = dJ/dx) strengthens as a compressed cell's faces widen;
  // the filtered step holds only the rest dashpot implicitly, and past twice it the explicit
  // part flips the velocity every step. Capped (volume_dashpot_cap), a pure volume rate v = g
  // meets the work rate -f . v / |v|^2 = c_c |g|^2 min(1, |g_rest'|^2 / |g'|^2), g' the columns
  // 1..dim: capped where a squeeze widens the faces, untouched where the cell shrinks evenly
  // (its faces narrow). One cell, exact arithmetic: 1e-12.
  const Mesh<dim> m = unit_simplex<dim>();
  const double c = 2.0;
  CellVolumes<dim> cv = make_cell_volumes<dim>(m.cells, m.points, Eigen::VectorXd::Constant(1, 1.0), c);
  Eigen::Matrix<double, dim, dim + 1> g0, g;
  volume_ratio_gradients<dim>(edge_matrix<dim>(cv.cell[0], [&](int i) { return Vec<dim>(m.points.col(i)); }),
                              cv.inverse_rest_det[0], g0);
  const double rest = g0.template rightCols<dim>().squaredNorm();
  for (const double squeeze : {0.3, 1.0}) { // height to 0.3 and widened (volume kept); shrunk evenly to 0.8
    Mat<dim> F = Mat<dim>::Identity() / std::sqrt(squeeze);
    F(dim - 1, dim - 1) = squeeze;
    if (squeeze == 1.0) F = 0.8 * Mat<dim>::Identity();
    const Nodal<dim> u = F * m.points - m.points;
    const auto x = [&](int i) -> Vec<dim> { return m.points.col(i) + u.col(i); };
    volume_ratio_gradients<dim>(edge_matrix<dim>(cv.cell[0], x), cv.inverse_rest_det[0], g);
    Nodal<dim> v(dim, dim + 1), f = Nodal<dim>::Zero(dim, dim + 1), f0 = Nodal<dim>::Zero(dim, dim + 1);
    for (int a = 0; a <= dim; ++a) v.col(cv.cell[0][static_cast<std::size_t>(a)]) = g.col(a);
    add_volume_forces<dim>(cv, m.points, u, v, f, 0.0);
    add_volume_forces<dim>(cv, m.points, u, Nodal<dim>::Zero(dim, dim + 1), f0, 0.0); // the elastic part
    const double rate = -((f - f0).cwiseProduct(v)).sum() / v.squaredNorm();
    const double now = g.template rightCols<dim>().squaredNorm();
    const double expected = c * g.squaredNorm() * std::min(1.0, rest / now);
    EXPECT_NEAR(rate, expected, 1e-12 * expected) << "squeeze " << squeeze;
    if (squeeze < 1) {
      EXPECT_GT(now, 1.2 * rest); // the case the cap is for
    } else {
      EXPECT_NEAR(rate, c * g.squaredNorm(), 1e-12 * expected); // no cap where the faces narrow
    }
  }
}

TEST(CellVolumeDashpot, NeverDampsACompressedCellMoreThanAtRest2D) {
  check_dashpot_cap<2>();
}
TEST(CellVolumeDashpot, NeverDampsACompressedCellMoreThanAtRest3D) {
  check_dashpot_cap<3>();
}

} // namespace
} // namespace vtb
