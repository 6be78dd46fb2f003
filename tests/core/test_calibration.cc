// Lumped masses and spring calibration against closed forms.
#include "vtb/meshes/generate.hh"
#include "vtb/springs/calibration.hh"
#include "vtb/springs/spring_network.hh"

#include <gtest/gtest.h>

#include <cmath>

namespace vtb {
namespace {

Mesh2 equilateral() {
  Mesh2 m;
  m.points.resize(2, 3);
  m.points << 0, 1, 0.5, 0, 0, std::sqrt(3.0) / 2;
  m.cells = {{0, 1, 2}};
  return m;
}

TEST(Calibration, EquilateralTriangleMatchesLatticeStiffness) {
  // A triangular lattice of springs k has 2D Young's modulus 2k/sqrt(3) and nu = 1/3, so one
  // triangle contributes k = sqrt(3)/4 E t to each edge. Both calibrations reproduce it
  // (Lloyd's fit exactly at nu = 1/3, where the spring element equals the FEM element).
  const double E = 2.0e4, t = 0.01, expected = std::sqrt(3.0) / 4 * E * t;
  const Eigen::VectorXd kl = lloyd_stiffness(equilateral(), E, 1.0 / 3.0, t);
  const Eigen::VectorXd kv = van_gelder_stiffness(equilateral(), E, t);
  for (int e = 0; e < 3; ++e) {
    EXPECT_NEAR(kl[e], expected, 1e-10 * expected);
    EXPECT_NEAR(kv[e], expected, 1e-10 * expected);
  }
}

TEST(Calibration, LloydFitIsExactOnlyAtTheCauchyPoissonRatio) {
  const Mesh2 m = equilateral();
  const double E = 1.0, t = 1.0;
  auto residual = [&](double nu) {
    const Eigen::MatrixXd K = fem_element_stiffness(m, m.cells[0], E, nu, t);
    const Eigen::VectorXd k = lloyd_stiffness(m, E, nu, t);
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(6, 6);
    const auto edges = unique_edges(m);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const int a = edges[e][0], b = edges[e][1];
      const Eigen::Vector2d d = (m.points.col(b) - m.points.col(a)).normalized();
      const Eigen::Matrix2d nn = d * d.transpose() * k[static_cast<Eigen::Index>(e)];
      S.block<2, 2>(2 * a, 2 * a) += nn;
      S.block<2, 2>(2 * b, 2 * b) += nn;
      S.block<2, 2>(2 * a, 2 * b) -= nn;
      S.block<2, 2>(2 * b, 2 * a) -= nn;
    }
    return (S - K).norm() / K.norm();
  };
  EXPECT_LT(residual(1.0 / 3.0), 1e-12);
  EXPECT_GT(residual(0.45), 0.05) << "springs cannot represent nu far from 1/3";
}

TEST(Calibration, FemElementStiffnessHasRigidModesInItsNullSpace) {
  const Mesh3 box = generate_box({1, 1, 1}, {1, 1, 1});
  const Eigen::MatrixXd K = fem_element_stiffness(box, box.cells[0], 1.0, 0.3, 1.0);
  Eigen::VectorXd tx = Eigen::VectorXd::Zero(12), rz = Eigen::VectorXd::Zero(12);
  for (int a = 0; a < 4; ++a) {
    tx[3 * a] = 1;
    const Eigen::Vector3d p = box.points.col(box.cells[0][static_cast<std::size_t>(a)]);
    rz[3 * a] = -p.y();
    rz[3 * a + 1] = p.x();
  }
  EXPECT_LT((K * tx).norm(), 1e-12 * K.norm());
  EXPECT_LT((K * rz).norm(), 1e-12 * K.norm());
}

TEST(Calibration, LumpedMassesSumToTheBodyMass) {
  const Mesh2 plate = generate_rectangle({0.2, 0.05}, {8, 3});
  EXPECT_NEAR(lumped_masses(plate, 1000.0, 0.002).sum(), 1000.0 * 0.2 * 0.05 * 0.002, 1e-15);
  const Mesh3 box = generate_box({0.3, 0.2, 0.1}, {3, 2, 2});
  EXPECT_NEAR(lumped_masses(box, 500.0, 1.0).sum(), 500.0 * 0.3 * 0.2 * 0.1, 1e-14);
}

TEST(Calibration, NetworkHasOneSpringPerEdgeWithDashpotsTauK) {
  MaterialDesc mat;
  mat.young_modulus = 1e4;
  mat.poisson_ratio = 0.3;
  mat.density = 1000;
  mat.thickness = 0.001;
  mat.retardation_time = 0.2;
  const Mesh2 plate = generate_rectangle({1, 1}, {3, 3});
  const auto net = build_network(plate, mat, "van-gelder");
  // 16 nodes, 18 triangles: edges = 3 x 3 x 3 cells + 3 + 3 boundary rows = 33.
  EXPECT_EQ(net.num_springs(), 33);
  EXPECT_TRUE(net.damping.isApprox(0.2 * net.stiffness));
  EXPECT_EQ(net.adj_ptr.back(), 2 * net.num_springs());
}

/// The FEM stiffness as it used to be assembled: every element entry a triplet, summed by
/// setFromTriplets in the cells' order.
template <int dim> Eigen::SparseMatrix<double> triplet_stiffness(const Mesh<dim>& mesh, double E, double nu, double t) {
  std::vector<Eigen::Triplet<double>> trip;
  for (const auto& c : mesh.cells) {
    const Eigen::MatrixXd Ke = fem_element_stiffness(mesh, c, E, nu, t);
    for (int a = 0; a <= dim; ++a)
      for (int b = 0; b <= dim; ++b)
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j)
            trip.emplace_back(dim * c[static_cast<std::size_t>(a)] + i, dim * c[static_cast<std::size_t>(b)] + j,
                              Ke(a * dim + i, b * dim + j));
  }
  Eigen::SparseMatrix<double> K(dim * mesh.num_nodes(), dim * mesh.num_nodes());
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

TEST(Calibration, FemStiffnessAssembledInItsPatternEqualsTheTripletSum) {
  // The in-pattern assembly adds each entry's element contributions in the cells' order, as
  // setFromTriplets does: the same matrix to the bit, pattern and values, in 2D and 3D.
  const Mesh2 plate = generate_rectangle(Eigen::Vector2d(0.2, 0.05), Eigen::Vector2i(9, 4));
  const Mesh3 box = generate_box(Eigen::Vector3d(0.04, 0.03, 0.02), Eigen::Vector3i(4, 3, 2));
  const auto check = [](const auto& mesh, double t) {
    const Eigen::SparseMatrix<double> a = fem_stiffness_matrix(mesh, 5.0e4, 0.3, t);
    const Eigen::SparseMatrix<double> b = triplet_stiffness(mesh, 5.0e4, 0.3, t);
    ASSERT_EQ(a.nonZeros(), b.nonZeros());
    EXPECT_EQ(Eigen::MatrixXd(a), Eigen::MatrixXd(b));
  };
  check(plate, 0.001);
  check(box, 1.0);
}

} // namespace
} // namespace vtb
