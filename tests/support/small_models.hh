#pragma once
/// Small models built in code for the tests: a single Voigt element, plates from scenes.

#include "vtb/meshes/generate.hh"
#include "vtb/problem/scene.hh"
#include "vtb/solvers/integrator.hh"

#include <string>

namespace vtb::test {

/// One Voigt element along x: node 0 fixed at the origin, node 1 free at (L, 0) with mass m,
/// pulled by a step force F along x. The mesh is a placeholder triangle (unused).
inline Model<2> single_element(double k, double c, double m, double F, double L = 1.0) {
  Model<2> model;
  auto& net = model.net;
  net.rest.resize(2, 2);
  net.rest << 0, L, 0, 0;
  net.mass = Eigen::Vector2d(m, m);
  net.edge = {{0, 1}};
  net.rest_length = Eigen::VectorXd::Constant(1, L);
  net.stiffness = Eigen::VectorXd::Constant(1, k);
  net.damping = Eigen::VectorXd::Constant(1, c);
  net.adj_ptr = {0, 1, 2};
  net.adj_node = {1, 0};
  net.adj_spring = {0, 0};
  net.calibration = "test";
  model.mesh.points = net.rest; // two nodes and no cell: the problem's node count is the mesh's
  Support<2> fix;
  fix.name = "fix";
  fix.nodes = {0};
  model.supports.push_back(fix);
  Load<2> load;
  load.name = "pull";
  load.nodes = {1};
  load.force = Nodal<2>(2, 1);
  load.force << F, 0;
  model.loads.push_back(load);
  model.constrained = {1, 0};
  model.free_nodes = {1};
  model.free_index = {-1, 0};
  model.initial_velocity = Nodal<2>::Zero(2, 2);
  model.duration = 1.0;
  model.output_interval = 0.1;
  return model;
}

/// A scene text for a plate [0, 0.2] x [0, 0.05] (or `size`) with the given extra TOML appended.
inline std::string plate_scene(int nx, int ny, const std::string& extra, double tau = 0.05,
                               const std::string& size = "0.2, 0.05", double mass_damping = 0.0) {
  return "[scene]\nname = \"plate\"\nduration = 1.0\noutput_interval = 0.01\n"
         "[mesh]\ngenerate = { shape = \"rectangle\", size = [" +
         size + "], divisions = [" + std::to_string(nx) + ", " + std::to_string(ny) +
         "] }\n"
         "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3333\ndensity = 1000.0\nthickness = 0.001\n"
         "retardation_time = " +
         std::to_string(tau) + "\nmass_damping = " + std::to_string(mass_damping) + "\n" + extra;
}

/// A plate clamped on its left edge and pulled on its right by `force` (N), with `extra`
/// appended (probes, [solver]): the harness tests' common scene.
inline std::string pulled_plate(int nx, int ny, const std::string& extra, const std::string& force = "0.2, 0.0") {
  return plate_scene(nx, ny,
                     "[[fix]]\ngroup = \"left\"\n[[load]]\ngroup = \"right\"\ntotal_force = [" + force + "]\n" + extra);
}

/// Builds a 2D model from scene text.
inline Model<2> model_from(const std::string& text) {
  const Scene s = parse_scene(text, "test.toml", ".");
  return build_model<2>(s, std::get<Mesh2>(load_mesh(s)));
}

/// Total linear momentum sum m v and angular momentum sum m (x x v) (2D scalar).
inline Eigen::Vector2d momentum(const Model<2>& m, const State<2>& s) {
  return s.v * m.net.mass;
}
/// Angular momentum about the origin, and its natural scale sum m |x| |v| (to judge a change
/// of it relative to the terms that make it up, which may cancel).
inline double angular_momentum(const Model<2>& m, const State<2>& s, double* scale = nullptr) {
  double l = 0, sc = 0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Eigen::Vector2d x = m.net.rest.col(i) + s.u.col(i);
    l += m.net.mass[i] * (x.x() * s.v(1, i) - x.y() * s.v(0, i));
    sc += m.net.mass[i] * x.norm() * s.v.col(i).norm();
  }
  if (scale) *scale = sc;
  return l;
}

} // namespace vtb::test
