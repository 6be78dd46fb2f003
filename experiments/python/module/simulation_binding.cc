#include "bindings.hh"

#include "vtb/base/input_error.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/meshes/region.hh"
#include "vtb/problem/cell_fields.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/problem.hh"
#include "vtb/solvers/integrator.hh"
#include "vtb/stepper/live_sim.hh"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <variant>

namespace vtb::python {

namespace {

/// A scene stepped from Python: the interactive stepper LiveSim (core/stepper, the viewer's
/// too) in the mesh's dimension.
/// Arrays of the state are views of the simulation's own storage (no copy; valid while the
/// simulation lives, since reset and configure copy into that storage).
class Simulation {
public:
  Simulation(const Scene& scene, const SimControls& controls) {
    AnyMesh mesh = load_mesh(scene);
    std::visit(
        [&](auto& m) {
          constexpr int dim = std::decay_t<decltype(m)>::points_dim;
          m_sim = std::make_unique<LiveSim<dim>>(scene, std::move(m), controls, harness::continuum_yardstick());
        },
        mesh);
  }

  template <class F> decltype(auto) visit(F&& f) {
    return std::visit([&](auto& p) -> decltype(auto) { return f(*p); }, m_sim);
  }
  template <class F> decltype(auto) visit(F&& f) const {
    return std::visit([&](const auto& p) -> decltype(auto) { return f(std::as_const(*p)); }, m_sim);
  }
  int dim() const { return m_sim.index() == 0 ? 2 : 3; }

private:
  std::variant<std::unique_ptr<LiveSim<2>>, std::unique_ptr<LiveSim<3>>> m_sim;
};

/// A float64 view of an Eigen array of the simulation, kept alive by `owner`: a nodal matrix
/// (dim x n, column-major) read as (n, dim), a vector as (n,).
template <class Array> py::array array_view(const Array& a, const py::handle& owner, bool writeable) {
  constexpr auto d = py::ssize_t(sizeof(double));
  auto* data = const_cast<double*>(a.data()); // read-only views say so to numpy below
  py::array v = Array::ColsAtCompileTime == 1
                    ? py::array(py::dtype::of<double>(), {py::ssize_t(a.size())}, {d}, data, owner)
                    : py::array(py::dtype::of<double>(), {py::ssize_t(a.cols()), py::ssize_t(a.rows())},
                                {py::ssize_t(a.rows()) * d, d}, data, owner);
  if (!writeable) v.attr("setflags")(py::arg("write") = false);
  return v;
}

/// A property that views the array `pick` chooses of the simulation's LiveSim (no copy).
template <class Pick> auto nodal_property(Pick pick, bool writeable) {
  return [pick, writeable](const py::object& self) {
    return self.cast<Simulation&>().visit([&](auto& s) { return array_view(pick(s), self, writeable); });
  };
}

template <int dim> Vec<dim> to_vec(const std::vector<double>& x, const char* what) {
  if (static_cast<int>(x.size()) != dim)
    throw InputError(std::string(what) + ": expected " + std::to_string(dim) + " values, got " +
                     std::to_string(x.size()));
  Vec<dim> v;
  for (int d = 0; d < dim; ++d) v[d] = x[static_cast<std::size_t>(d)];
  return v;
}

template <int dim> int node_of(const LiveSim<dim>& s, const py::handle& where) {
  if (py::isinstance<py::int_>(where)) {
    const long node = where.cast<long>();
    if (node < 0 || node >= s.model().num_nodes())
      throw InputError("node " + std::to_string(node) + " out of range (the mesh has " +
                       std::to_string(s.model().num_nodes()) + " nodes)");
    return static_cast<int>(node);
  }
  return nearest_node(s.model().mesh, to_vec<dim>(where.cast<std::vector<double>>(), "point"));
}

/// The Simulation's arguments over `c` (each one given replaces c's value).
SimControls with_args(SimControls c, const std::optional<std::string>& solver, const std::optional<std::string>& filter,
                      std::optional<double> dt, const std::optional<std::string>& springs,
                      std::optional<double> stiffness_scale) {
  SolverOverrides{solver, filter, dt, springs}.apply(c.solver, c.filter, c.dt, c.springs);
  if (stiffness_scale) c.stiffness_scale = *stiffness_scale;
  return c;
}

/// Making, stepping and loading a simulation.
void def_stepping(py::class_<Simulation>& cls) {
  cls.def(py::init([](const py::object& scene, std::optional<std::string> solver, std::optional<std::string> filter,
                      std::optional<double> dt, std::optional<std::string> springs, double stiffness_scale) {
            const Scene s = to_scene(scene);
            SimControls scene_controls; // the scene's [solver]
            scene_controls.solver = s.solver.kind;
            scene_controls.filter = s.solver.step.filter;
            scene_controls.dt = s.solver.dt;
            scene_controls.springs = s.solver.springs;
            const SimControls c = with_args(scene_controls, solver, filter, dt, springs, stiffness_scale);
            py::gil_scoped_release release; // a spring fit may take seconds
            return std::make_unique<Simulation>(s, c);
          }),
          py::arg("scene"), py::arg("solver") = py::none(), py::arg("filter") = py::none(), py::arg("dt") = py::none(),
          py::arg("springs") = py::none(), py::arg("stiffness_scale") = 1.0)
      .def(
          "step",
          [](Simulation& self, long n) {
            if (n < 0) throw InputError("step: n must be >= 0");
            py::gil_scoped_release release;
            return self.visit([&](auto& s) { return s.steps(n); });
          },
          py::arg("n") = 1, "Advance n steps of dt (stops at a failure); returns the steps taken")
      .def(
          "configure",
          [](Simulation& self, std::optional<std::string> solver, std::optional<std::string> filter,
             std::optional<double> dt, std::optional<std::string> springs, std::optional<double> stiffness_scale) {
            self.visit([&](auto& s) {
              const SimControls c = with_args(s.controls(), solver, filter, dt, springs, stiffness_scale);
              py::gil_scoped_release release;
              s.configure(c);
            });
          },
          py::arg("solver") = py::none(), py::arg("filter") = py::none(), py::arg("dt") = py::none(),
          py::arg("springs") = py::none(), py::arg("stiffness_scale") = py::none(),
          "Change the solver, filter, dt, springs or stiffness between steps (the state is kept; "
          "InputError keeps the previous configuration)")
      .def(
          "reset", [](Simulation& self) { self.visit([](auto& s) { s.reset(); }); },
          "Back to the initial state (the external forces are kept)")
      .def(
          "apply_force",
          [](Simulation& self, const py::object& where, const std::vector<double>& force, double stiffness,
             double damping) {
            return self.visit([&](auto& s) {
              constexpr int dim = std::decay_t<decltype(s.model())>::dimension;
              const int node = node_of(s, where);
              if (!(stiffness >= 0) || !(damping >= 0))
                throw InputError("apply_force: stiffness and damping must be >= 0");
              s.external_force().col(node) = to_vec<dim>(force, "force");
              s.external_stiffness()[node] = stiffness;
              s.external_damping()[node] = damping;
              return node;
            });
          },
          py::arg("where"), py::arg("force"), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
          "Set the external force (N) on a node (an int) or on the node nearest a point, held until changed; "
          "stiffness (N/m) and damping (N s/m): of the coupling that makes it, which the implicit solvers take "
          "implicitly. Returns the node.")
      .def("clear_forces",
           [](Simulation& self) {
             self.visit([](auto& s) {
               s.external_force().setZero();
               s.external_stiffness().setZero();
               s.external_damping().setZero();
             });
           })
      .def(
          "nearest_node",
          [](const Simulation& self, const std::vector<double>& point) {
            return self.visit([&](const auto& s) {
              constexpr int dim = std::decay_t<decltype(s.model())>::dimension;
              return nearest_node(s.model().mesh, to_vec<dim>(point, "point"));
            });
          },
          py::arg("point"));
}

/// The state as views of the simulation's storage: sizes, time, displacements, velocities, forces.
void def_state(py::class_<Simulation>& cls) {
  cls.def_property_readonly("dim", &Simulation::dim)
      .def_property_readonly(
          "num_nodes",
          [](const Simulation& self) { return self.visit([](const auto& s) { return s.model().num_nodes(); }); })
      .def_property_readonly(
          "num_springs",
          [](const Simulation& self) { return self.visit([](const auto& s) { return s.model().net.num_springs(); }); })
      .def_property_readonly(
          "time", [](const Simulation& self) { return self.visit([](const auto& s) { return s.state().t; }); })
      .def_property_readonly(
          "dt", [](const Simulation& self) { return self.visit([](const auto& s) { return s.controls().dt; }); })
      .def_property_readonly(
          "solver",
          [](const Simulation& self) { return self.visit([](const auto& s) { return s.controls().solver; }); })
      .def_property_readonly(
          "filter", [](const Simulation& self) { return self.visit([](const auto& s) { return s.running_filter(); }); },
          "The filter the filtered solver runs (auto resolved); empty for the other solvers")
      .def_property_readonly(
          "springs",
          [](const Simulation& self) { return self.visit([](const auto& s) { return s.model().net.calibration; }); },
          "The spring constants used (lloyd, van-gelder, fitted, volume, fitted-volume)")
      .def_property_readonly(
          "stable",
          [](const Simulation& self) { return self.visit([](const auto& s) { return s.failure().empty(); }); })
      .def_property_readonly(
          "failure", [](const Simulation& self) { return self.visit([](const auto& s) { return s.failure(); }); })
      .def_property_readonly("displacements",
                             nodal_property(
                                 [](auto& s) -> auto& { return s.state().u; }, false),
                             "u, (nodes, dim) m: a read-only view of the state (no copy)")
      .def_property_readonly("velocities",
                             nodal_property(
                                 [](auto& s) -> auto& { return s.state().v; }, false),
                             "v, (nodes, dim) m/s: a read-only view of the state (no copy)")
      .def_property_readonly(
          "external_forces",
          nodal_property(
              [](auto& s) -> auto& { return s.external_force(); }, true),
          "(nodes, dim) N: a writable view of the forces applied from outside at every step (no copy)")
      .def_property_readonly("external_stiffness",
                             nodal_property(
                                 [](auto& s) -> auto& { return s.external_stiffness(); }, true),
                             "(nodes,) N/m: a writable view of the couplings' stiffness that makes the external forces")
      .def_property_readonly("external_damping",
                             nodal_property(
                                 [](auto& s) -> auto& { return s.external_damping(); }, true),
                             "(nodes,) N s/m: a writable view of the couplings' damping")
      .def_property_readonly(
          "rest_positions",
          [](const Simulation& self) {
            return self.visit([](const auto& s) { return Eigen::MatrixXd(s.model().net.rest.transpose()); });
          },
          "X, (nodes, dim) m (a copy)")
      .def_property_readonly(
          "positions",
          [](const Simulation& self) {
            return self.visit(
                [](const auto& s) { return Eigen::MatrixXd((s.model().net.rest + s.state().u).transpose()); });
          },
          "X + u, (nodes, dim) m (computed: a copy)");
}

/// What the state gives: internal forces, spring and cell strains.
void def_fields(py::class_<Simulation>& cls) {
  cls.def(
         "internal_forces",
         [](const Simulation& self) {
           return self.visit([](const auto& s) {
             auto f = s.state().u;
             f.setZero();
             add_internal_forces(s.model().net, s.state().u, s.state().v, f);
             return Eigen::MatrixXd(f.transpose());
           });
         },
         "The springs' and dashpots' forces on each node now, (nodes, dim) N")
      .def(
          "spring_strains",
          [](const Simulation& self) {
            return self.visit([](const auto& s) {
              const auto& net = s.model().net;
              Eigen::VectorXd e(net.num_springs());
              for (int k = 0; k < net.num_springs(); ++k) {
                const auto [i, j] = net.edge[static_cast<std::size_t>(k)];
                e[k] = ((net.rest.col(j) + s.state().u.col(j)) - (net.rest.col(i) + s.state().u.col(i))).norm() /
                           net.rest_length[k] -
                       1.0;
              }
              return e;
            });
          },
          "l / L0 - 1 per spring, (springs,)")
      .def(
          "cell_strains",
          [](const Simulation& self) {
            return self.visit([](const auto& s) {
              std::vector<float> out;
              cell_max_principal_strain(s.model().mesh, s.state().u, out);
              return py::array_t<float>(static_cast<py::ssize_t>(out.size()), out.data());
            });
          },
          "max |eigenvalue| of the Green strain per cell, (cells,)");
}

/// The mesh and the run: springs, cells, probes, the stepper's statistics.
void def_mesh(py::class_<Simulation>& cls) {
  cls.def_property_readonly(
         "springs_nodes",
         [](const Simulation& self) {
           return self.visit([](const auto& s) {
             const auto& e = s.model().net.edge;
             py::array_t<int> a({static_cast<py::ssize_t>(e.size()), py::ssize_t(2)});
             auto r = a.mutable_unchecked<2>();
             for (std::size_t k = 0; k < e.size(); ++k) r(py::ssize_t(k), 0) = e[k][0], r(py::ssize_t(k), 1) = e[k][1];
             return a;
           });
         },
         "(springs, 2): the two nodes of each spring")
      .def_property_readonly(
          "cells",
          [](const Simulation& self) {
            return self.visit([](const auto& s) {
              const auto& mesh = s.model().mesh;
              constexpr int nv = std::decay_t<decltype(s.model())>::dimension + 1;
              py::array_t<int> a({static_cast<py::ssize_t>(mesh.num_cells()), py::ssize_t(nv)});
              auto r = a.mutable_unchecked<2>();
              for (int c = 0; c < mesh.num_cells(); ++c)
                for (int k = 0; k < nv; ++k)
                  r(c, k) = mesh.cells[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)];
              return a;
            });
          },
          "(cells, dim + 1): each triangle's or tetrahedron's nodes")
      .def_property_readonly(
          "probes",
          [](const Simulation& self) {
            return self.visit([](const auto& s) {
              py::dict d;
              for (const auto& [name, node] : s.model().probes) d[py::str(name)] = node;
              return d;
            });
          },
          "{probe name: node}")
      .def_property_readonly(
          "stats",
          [](Simulation& self) {
            return self.visit([](auto& s) {
              s.refresh_stats();
              const auto& st = s.stats();
              py::dict d;
              d["steps"] = st.steps;
              d["step_median_us"] = st.step_median_us;
              d["realtime_factor"] = st.realtime_factor;
              d["energy"] = st.energy;
              d["max_strain"] = st.max_strain;
              d["fallback_steps"] = st.fallback_steps;
              d["step_budget_us"] = st.step_budget_us;
              d["steps_over_budget"] = st.steps_over_budget;
              d["filter_reason"] = st.filter_reason;
              d["courant_dt"] = s.courant_dt();
              return d;
            });
          },
          "Readouts, brought up to date when read: steps, step_median_us (over the last 256 steps), "
          "realtime_factor (of the last step call), energy (J), max_strain (springs' max |l/L0 - 1|), "
          "fallback_steps, step_budget_us and steps_over_budget ([solver].step_budget; 0 without), "
          "filter_reason (why auto picked the filter within the budget), courant_dt")
      .def("__repr__", [](const Simulation& self) {
        return self.visit([&](const auto& s) {
          return "<vtb.Simulation " + std::to_string(self.dim()) + "D, " + std::to_string(s.model().num_nodes()) +
                 " nodes, " + s.controls().solver +
                 (s.running_filter().empty() ? "" : " (" + s.running_filter() + ")") +
                 ", t = " + std::to_string(s.state().t) + " s>";
        });
      });
}

} // namespace

void bind_simulation(py::module_& m) {
  py::class_<Simulation> cls(m, "Simulation", R"(A scene you step yourself, one fixed step at a time.

Simulation(scene, solver=None, filter=None, dt=None, springs=None, stiffness_scale=1.0):
`scene` is a vtb.Scene, a path or a dict; the other arguments override its [solver]. The
steppers are the fixed-step spring solvers (explicit, filtered and its filters,
implicit-euler); CVODE and the FEM produce whole runs (vtb.run, vtb.compare). The GIL is
released while it steps, so another Python thread (a device loop) runs meanwhile.)");
  def_stepping(cls);
  def_state(cls);
  def_fields(cls);
  def_mesh(cls);
}

} // namespace vtb::python
