// `fitted-nodal` under homogeneous deformations against neo-Hookean's closed forms (the reference
// FEM's W = mu/2 (tr C - 3) - mu ln J + lambda/2 ln^2 J): confined compression, simple shear and
// uniaxial compression and tension (laterally free). Every node is moved by F; the network's mean
// first Piola stress is its virial, P = -(1/V) sum_a f_a (X_a - c)^T (dE/dF for an affine
// motion). docs/volume_term.md, "Where it departs from neo-Hookean", quotes the table this prints.
#include "support/fresh_dir.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/springs/spring_network.hh"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>

namespace vtb {
namespace {

using M3 = Eigen::Matrix3d;

M3 neo_hookean(const M3& F, double mu, double lambda) {
  const M3 f_inv_t = F.inverse().transpose();
  return mu * (F - f_inv_t) + lambda * std::log(F.determinant()) * f_inv_t;
}

/// The network's mean first Piola stress under x = c + F (X - c) on every node.
M3 virial_stress(const SpringNetwork<3>& net, const Mesh3& mesh, double volume, const M3& F) {
  const int n = mesh.num_nodes();
  const Eigen::Vector3d c = mesh.points.rowwise().mean();
  Nodal<3> u(3, n), v = Nodal<3>::Zero(3, n), f = Nodal<3>::Zero(3, n);
  for (int i = 0; i < n; ++i) u.col(i) = (F - M3::Identity()) * (mesh.points.col(i) - c);
  add_internal_forces(net, u, v, f);
  M3 p = M3::Zero();
  for (int i = 0; i < n; ++i) p -= f.col(i) * (mesh.points.col(i) - c).transpose();
  return p / volume;
}

/// Uniaxial stretch s along z, laterally free: the lateral stretch t with P_xx = 0 (Newton with a
/// difference quotient), and P_zz there.
double uniaxial(const std::function<M3(const M3&)>& law, double s) {
  const auto at = [s](double t) {
    M3 F = M3::Identity();
    F(0, 0) = F(1, 1) = t;
    F(2, 2) = s;
    return F;
  };
  double t = 1.0;
  for (int it = 0; it < 30; ++it) {
    const double r = law(at(t))(0, 0), h = 1e-7;
    t -= r / ((law(at(t + h))(0, 0) - r) / h);
  }
  return law(at(t))(2, 2);
}

TEST(HomogeneousStrain, FittedNodalIsNeoHookeanAtSmallStrainOnEveryMesh) {
  // At 1 % strain the network is the linear continuum the fit trains it to be (its training holds
  // the supported body's uniform stress states; docs/fidelity.md), so it meets the 5 % small-strain
  // goal in uniaxial stress and simple shear (the closed forms) on a coarse and a finer
  // box; neo-Hookean there is the linear law to 1 %. Confined compression (the bulk response, a
  // state the supported body's training holds only in part) is printed: at nu 0.45 it is 12 %
  // (4^3) and 7 % (6^3) stiff, approaching as the box refines.
  // The large-strain rows are printed, not bounded: there the network is its own law (it moves by
  // at most a few per cent between the two boxes) and departs from neo-Hookean as
  // docs/volume_term.md records.
  const test::FreshDir dir;
  ::setenv("VTB_CACHE_DIR", dir.path().c_str(), 1);
  const double E = 5.0e3, L = 0.02;
  for (const int cells : {4, 6}) {
    const Mesh3 mesh = generate_box({L, L, L}, {cells, cells, cells});
    std::vector<int> base;
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (mesh.points(2, v) < 1e-12) base.push_back(v);
    for (const double nu : {0.3, 0.45}) {
      const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
      const SpringNetwork<3> net = build_network(mesh, MaterialDesc{E, nu, 1000, 1, 0, 0}, "fitted-nodal", base);
      ASSERT_EQ(net.calibration, "fitted-nodal");
      const auto network = [&](const M3& F) { return virial_stress(net, mesh, L * L * L, F); };
      const auto continuum = [&](const M3& F) { return neo_hookean(F, mu, lambda); };
      struct State {
        const char* name;
        std::function<double(const std::function<M3(const M3&)>&, double)> stress;
      };
      const State states[] = {{"confined",
                               [](const auto& law, double s) {
                                 M3 F = M3::Identity();
                                 F(2, 2) = s;
                                 return law(F)(2, 2);
                               }},
                              {"shear",
                               [](const auto& law, double g) {
                                 M3 F = M3::Identity();
                                 F(0, 2) = g - 1;
                                 return law(F)(0, 2);
                               }},
                              {"uniaxial", [](const auto& law, double s) { return uniaxial(law, s); }}};
      std::cout << cells << "^3 box, nu " << nu << " (P / mu: network, neo-Hookean):" << std::fixed
                << std::setprecision(3);
      for (const State& st : states) {
        const double small_net = st.stress(network, 0.99), small_nh = st.stress(continuum, 0.99);
        if (std::string(st.name) != "confined") { // the two closed forms
          EXPECT_NEAR(small_net / small_nh, 1.0, 0.05) << st.name << ", " << cells << "^3, nu " << nu;
        }
        std::cout << "\n  " << st.name;
        for (const double s : {0.99, 0.8, 0.6, 1.2, 1.4, 1.6})
          if (std::string(st.name) != "confined" || s < 1)
            std::cout << "  " << s << ": " << st.stress(network, s) / mu << " " << st.stress(continuum, s) / mu;
      }
      std::cout << "\n" << std::defaultfloat;
    }
  }
  ::unsetenv("VTB_CACHE_DIR");
}

} // namespace
} // namespace vtb
