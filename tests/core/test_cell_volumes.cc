// The volume term per cell (cell_volumes.hh): its force is minus its energy's gradient, in 2D
// and 3D and through inversion; a cell pressed through its base is pushed back, where the pair
// springs hold the mirrored cell at no cost; the element fit (lloyd_volume_stiffness) gives
// the term lambda's excess over the lattice's Cauchy part.
//
// Tolerances: central differences of a cubic (3D) or quadratic (2D) polynomial energy with step
// h have truncation error ~ h^2 |E'''| (1e-12 of the force at h = 1e-6 of the cell) and
// round-off ~ eps E / h (~ 1e-10 of it); 1e-7 of the largest force bounds both, while a sign
// error or a dropped term is O(1) of it.
#include "vtb/solvers/integrator.hh"
#include "vtb/solvers/simulation.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/force_jacobian.hh"
#include "vtb/springs/spring_network.hh"

#include "support/central_differences.hh"
#include "support/small_models.hh"

#include <gtest/gtest.h>

#include <algorithm>
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

/// A cell's volume term with k_c = 1 and no dashpot.
template <int dim> CellVolumes<dim> one_cell(const Mesh<dim>& m) {
  return make_cell_volumes<dim>(m.cells, m.points, Eigen::VectorXd::Ones(1), 0.0);
}

template <int dim> void check_force_is_minus_the_gradient(unsigned seed) {
  const Mesh<dim> m = unit_simplex<dim>();
  const CellVolumes<dim> cv = one_cell(m);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-0.8, 0.8);
  int inverted = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Nodal<dim> u(dim, dim + 1);
    for (Eigen::Index k = 0; k < u.size(); ++k) u.data()[k] = r(gen);
    inverted += volume_ratios<dim>(m.cells, m.points, u).inverted;
    const Nodal<dim> v = Nodal<dim>::Zero(dim, dim + 1);
    Nodal<dim> f = Nodal<dim>::Zero(dim, dim + 1);
    add_volume_forces(cv, m.points, u, v, f, 0.0);
    const Nodal<dim> fd = test::minus_energy_gradient(cv, m.points, u, 1e-6);
    EXPECT_LT((f - fd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, f.cwiseAbs().maxCoeff())) << "trial " << trial;
    // A translation does no work: the forces sum to zero.
    EXPECT_LT(f.rowwise().sum().norm(), 1e-12 * std::max(1.0, f.cwiseAbs().maxCoeff()));
  }
  EXPECT_GT(inverted, 0) << "some trials pass through inversion";
}

TEST(CellVolumes, ForceIsMinusTheEnergysGradientThroughInversion2D) {
  check_force_is_minus_the_gradient<2>(3);
}
TEST(CellVolumes, ForceIsMinusTheEnergysGradientThroughInversion3D) {
  check_force_is_minus_the_gradient<3>(4);
}

TEST(CellVolumes, TheDashpotDampsTheVolumeRateAlone) {
  // c_c = tau k_c: a velocity field that changes the volume at rate dJ/dt meets -c_c dJ/dt
  // grad J; a rigid rotation's (dJ/dt = 0) meets nothing.
  const Mesh<3> m = unit_simplex<3>();
  const CellVolumes<3> cv = make_cell_volumes<3>(m.cells, m.points, Eigen::VectorXd::Constant(1, 2.0), 0.1);
  const Nodal<3> u = Nodal<3>::Zero(3, 4);
  Nodal<3> f = Nodal<3>::Zero(3, 4);
  Nodal<3> spin(3, 4); // omega x X, omega = (0, 0, 1)
  for (int a = 0; a < 4; ++a) spin.col(a) = Vec<3>(0, 0, 1).cross(m.points.col(a));
  add_volume_forces(cv, m.points, u, spin, f, 0.0);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-15);
  const Nodal<3> expand = m.points; // v = X: dJ/dt = tr(grad v) = 3
  f.setZero();
  add_volume_forces(cv, m.points, u, expand, f, 0.0);
  // f_a = -c dJ/dt g_a with g the rest gradients: node 1's is (1, 0, 0).
  EXPECT_NEAR(f(0, 1), -0.2 * 3.0, 1e-14);
  EXPECT_NEAR(f(1, 1), 0.0, 1e-14);
}

/// The apex of a cell pushed through its base, to the mirror image of its rest position: every
/// edge has its rest length again, so the pair springs carry no force there; the volume term
/// (J = -1) pushes the apex back toward the side it came from.
template <int dim> void check_pushed_back() {
  const Mesh<dim> m = unit_simplex<dim>();
  const MaterialDesc mat{1e4, 0.45, 1000.0, 1.0, 0.0, 0.0};
  const SpringNetwork<dim> springs = build_network(m, mat, "lloyd");
  const SpringNetwork<dim> volume = build_network(m, mat, "volume");
  ASSERT_GT(volume.volume.stiffness[0], 0.0);
  Nodal<dim> u = Nodal<dim>::Zero(dim, dim + 1);
  u(dim - 1, dim) = -2.0; // the apex (0, .., 1) to (0, .., -1)
  EXPECT_EQ(volume_ratios<dim>(m.cells, m.points, u).inverted, 1);
  EXPECT_NEAR(volume_ratios<dim>(m.cells, m.points, u).min_ratio, -1.0, 1e-14);
  const Nodal<dim> v = Nodal<dim>::Zero(dim, dim + 1);
  Nodal<dim> f_springs = Nodal<dim>::Zero(dim, dim + 1), f_volume = f_springs;
  add_internal_forces(springs, u, v, f_springs);
  add_internal_forces(volume, u, v, f_volume);
  EXPECT_LT(f_springs.cwiseAbs().maxCoeff(), 1e-12 * springs.stiffness.maxCoeff()) << "the mirrored cell is at rest";
  // The apex is pushed up (toward its side), with the volume term's force 2 k_c |g| = 2 k_c.
  EXPECT_GT(f_volume(dim - 1, dim), 0.0);
  EXPECT_NEAR(f_volume(dim - 1, dim), 2.0 * volume.volume.stiffness[0], 1e-9 * volume.volume.stiffness[0]);
}

TEST(CellVolumes, ACellPressedThroughItsBaseIsPushedBack2D) {
  check_pushed_back<2>();
}
TEST(CellVolumes, ACellPressedThroughItsBaseIsPushedBack3D) {
  check_pushed_back<3>();
}

/// The element fit on a regular simplex (the equilateral triangle, the regular tetrahedron):
/// k_c grows with lambda, and the fitted element's stiffness is closer to the FEM element's
/// than Lloyd's springs alone (by at least half: Lloyd's miss lambda's excess entirely).
template <int dim> Mesh<dim> regular_simplex() {
  Mesh<dim> m = unit_simplex<dim>();
  if constexpr (dim == 2)
    m.points << 0, 1, 0.5, 0, 0, std::sqrt(3.0) / 2;
  else
    m.points << 1, -1, -1, 1, 1, -1, 1, -1, 1, 1, -1, -1;
  if (signed_measure(m, m.cells[0]) < 0) std::swap(m.cells[0][0], m.cells[0][1]);
  return m;
}

template <int dim> Eigen::MatrixXd network_stiffness(const SpringNetwork<dim>& net) {
  const Nodal<dim> u = Nodal<dim>::Zero(dim, net.num_nodes());
  const std::vector<int> all = [&] {
    std::vector<int> v(static_cast<std::size_t>(net.num_nodes()));
    for (int i = 0; i < net.num_nodes(); ++i) v[static_cast<std::size_t>(i)] = i;
    return v;
  }();
  return Eigen::MatrixXd(free_stiffness(net, u, all, net.num_nodes(), false));
}

template <int dim> void check_element_fit() {
  const Mesh<dim> m = regular_simplex<dim>();
  const double E = 1e4, cauchy = spring_poisson_ratio(dim);
  Eigen::VectorXd cell_k;
  const Eigen::VectorXd k = lloyd_volume_stiffness(m, E, cauchy, 1.0, cell_k);
  // At the lattice's own ratio in 2D: no volume term (to the fit's round-off), Lloyd's springs
  // (an equilateral triangle's three edges make an isotropic lattice). A tetrahedron's six
  // edges do not (sum n^4 over them is not isotropic), so in 3D the fit keeps some volume term
  // there too; what holds in both is that the term grows with nu.
  if constexpr (dim == 2) {
    EXPECT_LT(cell_k[0], 1e-10 * k.maxCoeff());
    EXPECT_LT((k - lloyd_stiffness(m, E, cauchy, 1.0)).cwiseAbs().maxCoeff(), 1e-10 * k.maxCoeff());
  }
  double last = cell_k[0];
  for (double nu : {0.35, 0.4, 0.45, 0.49}) {
    const MaterialDesc mat{E, nu, 1000.0, 1.0, 0.0, 0.0};
    const Eigen::MatrixXd Kfem = fem_element_stiffness(m, m.cells[0], E, nu, 1.0);
    const double with = (network_stiffness(build_network(m, mat, "volume")) - Kfem).norm();
    const double without = (network_stiffness(build_network(m, mat, "lloyd")) - Kfem).norm();
    lloyd_volume_stiffness(m, E, nu, 1.0, cell_k);
    EXPECT_GT(cell_k[0], last) << "nu " << nu;
    last = cell_k[0];
    EXPECT_LT(with, 0.5 * without) << "nu " << nu;
  }
}

TEST(CellVolumes, TheElementFitGivesTheTermLambdasExcessOverTheLattice2D) {
  check_element_fit<2>();
}
TEST(CellVolumes, TheElementFitGivesTheTermLambdasExcessOverTheLattice3D) {
  check_element_fit<3>();
}

TEST(CellVolumes, TheTensorFilterRefusesTheTermInOneLineAndAutoRunsTheScalarFilter) {
  std::string text = test::pulled_plate(12, 3, "[solver]\nsprings = \"volume\"\n");
  text.replace(text.find("poisson_ratio = 0.3333"), 22, "poisson_ratio = 0.45");
  const Model<2> model = test::model_from(text);
  IntegratorOptions o;
  o.kind = "filtered";
  o.dt = 1e-3;
  o.filter = "tensor";
  try {
    make_integrator(model, o);
    ADD_FAILURE() << "the tensor filter took the volume term";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("[solver].filter = \"tensor\""), std::string::npos) << what;
    EXPECT_NE(what.find("springs = \"volume\""), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line";
  }
  EXPECT_EQ(chosen_filter(model, "auto"), "full");
  const Model<2> springs = test::model_from(test::pulled_plate(12, 3, "[solver]\nsprings = \"lloyd\"\n"));
  EXPECT_EQ(chosen_filter(springs, "auto"), "tensor") << "the springs alone keep auto's lag-free filter";
}

TEST(CellVolumes, TheRunReportsTheTermsCellsAndTheSmallestVolumeRatio) {
  // summary.json's extras for a spring run: `volume_cells` (the term's cells, only with the
  // term), `min_volume_ratio` and `inverted_cells` (every spring run). The plate pulled at its
  // right end stretches: its cells grow (J >= 1 up to the Poisson contraction), none inverts,
  // and the smallest J is within the run's max strain of 1 (a cell's J - 1 is a sum of at most
  // dim strains of that size).
  for (const std::string springs : {"volume", "lloyd"}) {
    const Model<2> model = test::model_from(test::pulled_plate(12, 3, "[solver]\nsprings = \"" + springs + "\"\n"));
    IntegratorOptions o;
    o.kind = "implicit-euler";
    o.dt = 1e-3;
    Trajectory<2> tr;
    const RunReport r = simulate(model, o, tr, false);
    ASSERT_TRUE(r.stable) << springs;
    const auto extra = [&](const std::string& key) {
      const auto it = std::find_if(r.extra.begin(), r.extra.end(), [&](const auto& e) { return e.first == key; });
      return it == r.extra.end() ? std::nan("") : it->second;
    };
    if (springs == "volume")
      EXPECT_EQ(extra("volume_cells"), model.mesh.num_cells());
    else
      EXPECT_TRUE(std::isnan(extra("volume_cells"))) << "no term, no count";
    EXPECT_EQ(extra("inverted_cells"), 0) << springs;
    const double J = extra("min_volume_ratio");
    EXPECT_GT(r.max_strain, 0) << springs;
    EXPECT_LE(J, 1.0) << springs;
    EXPECT_GE(J, 1.0 - 2 * r.max_strain) << springs;
  }
}

} // namespace
} // namespace vtb
