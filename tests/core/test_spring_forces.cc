// The spring kernel of every integrator (core/springs/src/spring_forces.cc: gather, vectorised
// coefficients, scatter, in chunks of 256 springs) against the per-element reference
// voigt_force summed spring by spring, and the divider-free inverse square root it uses.
#include "vtb/meshes/generate.hh"
#include "vtb/springs/spring_network.hh"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace vtb {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

TEST(NewtonInverseSqrt, IsWithinRoundOffOverTheWholeRange) {
  // Four Newton steps from a 3.5 % seed leave a truncation error of ~1e-21 (spring_kernels.hh),
  // far below round-off; each step rounds a few times, so 4 eps bounds what remains (the
  // measured worst case is 1.3 ulp). 10^-150 .. 10^150 covers every length squared a mesh in
  // metres, millimetres or kilometres can produce.
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> exponent(-150.0, 150.0);
  double worst = 0;
  for (int t = 0; t < 200000; ++t) {
    const double x = std::pow(10.0, exponent(gen));
    const long double exact = 1.0L / std::sqrt(static_cast<long double>(x));
    worst = std::max(worst, static_cast<double>(std::fabs((newton_inverse_sqrt(x) - exact) / exact)));
  }
  EXPECT_LE(worst, 4 * kEps);
  EXPECT_EQ(newton_inverse_sqrt(0.25), 2.0); // exact where the answer is representable
}

/// f from the reference kernel, spring by spring, in double: what add_internal_forces must equal.
template <int dim>
Nodal<dim> reference_forces(const SpringNetwork<dim>& net, const Nodal<dim>& u, const Nodal<dim>& v, double extra) {
  Nodal<dim> f = Nodal<dim>::Zero(dim, net.num_nodes());
  for (int s = 0; s < net.num_springs(); ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const Vec<dim> fi =
        voigt_force<dim>(net.rest.col(i) + u.col(i), net.rest.col(j) + u.col(j), v.col(i), v.col(j), net.rest_length[s],
                         net.stiffness[s], net.damping[s] + extra * net.stiffness[s]);
    f.col(i) += fi;
    f.col(j) -= fi;
  }
  f -= net.mass_damping * (v * net.mass.asDiagonal());
  return f;
}

template <int dim> void check_against_reference(const Mesh<dim>& mesh) {
  const MaterialDesc mat{5.0e4, 0.3, 1000.0, 0.05, 0.01, 2.0};
  const SpringNetwork<dim> net = build_network(mesh, mat, "lloyd");
  ASSERT_GT(net.num_springs(), 3 * 256) << "the mesh must span several chunks";
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> r(-1.0, 1.0);
  const double h = net.rest_length.minCoeff();
  Nodal<dim> u(dim, net.num_nodes()), v(dim, net.num_nodes());
  for (Eigen::Index c = 0; c < u.size(); ++c) {
    u.data()[c] = 0.2 * h * r(gen); // springs stretched and compressed by up to ~40 %
    v.data()[c] = h * r(gen);
  }
  // One spring collapsed to zero length: its element force is zero (voigt_force), not NaN.
  const int i0 = net.edge[5][0], j0 = net.edge[5][1];
  u.col(j0) = net.rest.col(i0) + u.col(i0) - net.rest.col(j0);
  Nodal<dim> f = Nodal<dim>::Zero(dim, net.num_nodes());
  add_internal_forces(net, u, v, f, 1e-3);
  const Nodal<dim> ref = reference_forces(net, u, v, 1e-3);
  ASSERT_TRUE(f.allFinite());
  // Per spring the two kernels differ only in 1/l (1.3 against 0.75 ulp) and the products
  // around it: under 10 eps of the element force, which is below k h here (strains up to ~40 %,
  // dashpot terms smaller). A node sums at most ~15 elements, so 15 * 10 eps * k h = 3.3e-14 k h
  // bounds the difference; 1e-13 k h (measured: 6e-16 k h).
  double scale = 0;
  for (int s = 0; s < net.num_springs(); ++s) scale = std::max(scale, net.stiffness[s] * h);
  EXPECT_LE((f - ref).cwiseAbs().maxCoeff(), 1e-13 * scale);
  // Adds to f rather than overwriting it.
  Nodal<dim> g = Nodal<dim>::Ones(dim, net.num_nodes());
  add_internal_forces(net, u, v, g, 1e-3);
  EXPECT_LE((g - f - Nodal<dim>::Ones(dim, net.num_nodes())).cwiseAbs().maxCoeff(), 1e-13 * scale);
}

TEST(SpringForces, EqualTheElementKernelSummedOnAPlate) {
  check_against_reference<2>(generate_rectangle({0.2, 0.05}, Eigen::Vector2i(40, 10)));
}

TEST(SpringForces, EqualTheElementKernelSummedOnABox) {
  check_against_reference<3>(generate_box({0.2, 0.05, 0.05}, Eigen::Vector3i(10, 4, 4)));
}

TEST(SpringForces, MakeTheTurnsInTheirOwnPass) {
  // add_internal_forces_and_turns gives add_internal_forces' forces to the bit and spring_turns'
  // per-spring turns to the bit (the same operations in the same order), and the turns are
  // their definition: per spring p = d . D, q = D x d; per node the sums over
  // its springs, which the two passes add in different orders (the fused pass flushes a node's
  // run at each chunk's end), as the definition does below. A sum of m terms in any order is
  // within (m - 1) eps sum |terms| of the exact one; m <= 8 here, so two orders differ by at
  // most 14 eps sum |terms| (measured: a few eps).
  const SpringNetwork<2> net = build_network(generate_rectangle({0.2, 0.05}, Eigen::Vector2i(40, 10)),
                                             MaterialDesc{5.0e4, 0.3, 1000.0, 0.05, 0.01, 2.0}, "lloyd");
  ASSERT_GT(net.num_springs(), 3 * 256) << "the mesh must span several chunks";
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> r(-1.0, 1.0);
  const double h = net.rest_length.minCoeff();
  const int n = net.num_nodes(), ns = net.num_springs();
  Nodal<2> u(2, n), v(2, n);
  for (Eigen::Index c = 0; c < u.size(); ++c) {
    u.data()[c] = 0.2 * h * r(gen);
    v.data()[c] = h * r(gen);
  }
  Eigen::VectorXd p(ns), q(ns), p2(ns), q2(ns);
  Nodal<2> rest(2, ns); // each spring's rest vector D, which the turns are given
  for (int s = 0; s < ns; ++s)
    rest.col(s) =
        net.rest.col(net.edge[static_cast<std::size_t>(s)][1]) - net.rest.col(net.edge[static_cast<std::size_t>(s)][0]);
  Eigen::Matrix2Xd sums = Eigen::Matrix2Xd::Constant(2, n, 7.0), sums2(2, n); // set, not added to
  Nodal<2> f = Nodal<2>::Zero(2, n), f2 = Nodal<2>::Zero(2, n);
  add_internal_forces_and_turns(net, u, v, f, 1e-3, SpringTurns{rest.data(), p.data(), q.data(), &sums});
  add_internal_forces(net, u, v, f2, 1e-3);
  spring_turns(net, u, SpringTurns{rest.data(), p2.data(), q2.data(), &sums2});
  EXPECT_TRUE(f == f2);
  EXPECT_TRUE(p == p2);
  EXPECT_TRUE(q == q2);
  Eigen::Matrix2Xd ref = Eigen::Matrix2Xd::Zero(2, n), size = Eigen::Matrix2Xd::Zero(2, n);
  int terms = 0;
  for (int s = 0; s < ns; ++s) {
    const int i = net.edge[static_cast<std::size_t>(s)][0], j = net.edge[static_cast<std::size_t>(s)][1];
    const Vec<2> D = net.rest.col(j) - net.rest.col(i), d = (net.rest.col(j) + u.col(j)) - (net.rest.col(i) + u.col(i));
    EXPECT_EQ(p[s], d.dot(D));
    EXPECT_EQ(q[s], D.x() * d.y() - D.y() * d.x());
    for (const int node : {i, j}) {
      ref.col(node) += Vec<2>(p[s], q[s]);
      size.col(node) += Vec<2>(std::abs(p[s]), std::abs(q[s]));
    }
  }
  for (int i = 0; i < n; ++i)
    terms = std::max(terms, net.adj_ptr[static_cast<std::size_t>(i) + 1] - net.adj_ptr[static_cast<std::size_t>(i)]);
  ASSERT_LE(terms, 8);
  for (const Eigen::Matrix2Xd* got : {&sums, &sums2})
    EXPECT_TRUE(((*got - ref).cwiseAbs().array() <= 14 * kEps * size.array()).all());
}

} // namespace
} // namespace vtb
