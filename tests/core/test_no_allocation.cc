// "No allocation in a time step": counts calls to malloc, calloc and realloc made by the
// test thread while integrators step. This program replaces malloc (glibc's __libc_*
// entry points do the work), so it is kept apart from the other suites.
#include "support/small_models.hh"
#include "vtb/haptics/contact2d.hh"
#include "vtb/haptics/contact3d.hh"
#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/force_shaping.hh"
#include "vtb/haptics/local_model.hh"
#include "vtb/meshes/generate.hh"
#include "vtb/solvers/tensor_filter.hh"

#include <gtest/gtest.h>
#ifdef VTB_HAVE_LIVE_SIM
#include "vtb/stepper/live_sim.hh"
#endif

#include <algorithm>
#include <cstdlib>
#include <ostream>

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
}

namespace {
thread_local bool g_counting = false;
thread_local long g_allocations = 0;
} // namespace

extern "C" void* malloc(std::size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  if (g_counting) ++g_allocations;
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_realloc(p, n);
}

namespace vtb {
namespace {

struct Case {
  std::string kind, filter, linear_solver = "auto";
};

std::ostream& operator<<(std::ostream& os, const Case& c) {
  return os << c.kind << " " << c.filter;
}

class NoAllocation : public ::testing::TestWithParam<Case> {};

TEST_P(NoAllocation, StepAllocatesNothing) {
  const std::string text = test::plate_scene(12, 3, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.2, 0.1]
)");
  Model<2> model = test::model_from(text);
  IntegratorOptions o;
  o.kind = GetParam().kind;
  o.filter = GetParam().filter;
  o.linear_solver = GetParam().linear_solver;
  o.dt = o.kind == "explicit" ? 1e-6 : 1e-3;
  o.strain_limit = 0.1;
  auto integ = make_integrator(model, o);
  State<2> s = initial_state(model);
  integ->step(s); // warm up
  // Sanity: the counter sees allocations at all.
  g_counting = true;
  void* p = std::malloc(64);
  g_counting = false;
  std::free(p);
  ASSERT_EQ(g_allocations, 1);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 50; ++k) integ->step(s);
  g_counting = false;
  EXPECT_EQ(g_allocations, 0) << o.kind << " " << o.filter;
}

INSTANTIATE_TEST_SUITE_P(Integrators, NoAllocation,
                         ::testing::Values(Case{"explicit", ""}, Case{"filtered", "full"},
                                           Case{"filtered", "neighbors"}, Case{"filtered", "tensor"},
                                           Case{"implicit-euler", "", "direct"}, Case{"implicit-euler", "", "cg"},
                                           Case{"implicit-euler", "", "cg-multigrid"}),
                         [](const auto& pinfo) {
                           std::string n = pinfo.param.kind + pinfo.param.filter +
                                           (pinfo.param.kind == "implicit-euler" ? pinfo.param.linear_solver : "");
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

/// Allocations during 20 filtered steps on `model` (after one warm-up step).
int filtered_step_allocations(const Model<2>& model, const char* filter) {
  IntegratorOptions o;
  o.kind = "filtered";
  o.filter = filter;
  auto integ = make_integrator(model, o);
  State<2> s = initial_state(model);
  integ->step(s);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 20; ++k) integ->step(s);
  g_counting = false;
  return g_allocations;
}

class CouplingsAllocateNothing : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(CouplingsAllocateNothing, WhileTheCoupledNodesAndTheirStiffnessChange) {
  // Pulls and contacts taken into the solve (State::applied_stiffness, applied_damping): the
  // coupled nodes change (Z made again), their stiffness changes (the capacitance factored
  // again), and the tensor filter's factor itself changes when the transverse cover moves;
  // none of it may allocate.
  const auto [kind, filter] = GetParam();
  Model<2> model = test::model_from(test::plate_scene(12, 3, "[[fix]]\ngroup = \"left\"\n"));
  IntegratorOptions o;
  o.kind = kind;
  o.filter = filter;
  o.dt = 1e-2;
  auto integ = make_integrator(model, o);
  State<2> s = initial_state(model);
  const auto n = model.num_nodes();
  s.applied = Nodal<2>::Zero(2, n);
  s.applied_stiffness = Eigen::VectorXd::Zero(n);
  s.applied_damping = Eigen::VectorXd::Zero(n);
  s.applied_group = Eigen::VectorXi::Constant(n, -1);
  integ->step(s);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 80; ++k) {
    s.applied_stiffness.setZero();
    s.applied_damping.setZero();
    s.applied.setZero();
    s.applied_group.setConstant(-1);
    for (int c = 0; c < 1 + k / 20; ++c) { // one, two, three coupled nodes, then four as a tip's footprint
      const auto node = n - 1 - c;
      s.applied_stiffness[node] = 100.0 * (1 + k % 3);
      s.applied_damping[node] = 0.5 * (k % 2);
      s.applied.col(node) = Vec<2>(0.0, -0.01);
      if (k >= 60) s.applied_group[node] = 0;
    }
    integ->step(s);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
}

INSTANTIATE_TEST_SUITE_P(ImplicitSolvers, CouplingsAllocateNothing,
                         ::testing::Values(std::pair{"filtered", "tensor"}, std::pair{"filtered", "full"},
                                           std::pair{"filtered", "tensor-multigrid"},
                                           std::pair{"implicit-euler", "auto"}),
                         [](const auto& pinfo) {
                           std::string n =
                               pinfo.param.first == std::string("filtered") ? pinfo.param.second : "implicit_euler";
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(NoAllocation, StepsWithTheVolumeTermAllocateNothing) {
  // springs = "volume" (the volume term per cell) at nu 0.45, in every integrator that takes it.
  std::string text = test::plate_scene(12, 3, R"(
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.2, 0.1]
[solver]
springs = "volume"
)");
  text.replace(text.find("poisson_ratio = 0.3333"), 22, "poisson_ratio = 0.45");
  const Model<2> volume = test::model_from(text);
  ASSERT_GT(volume.net.volume.stiffness.sum(), 0.0);
  // And with the stable energy's shear part in every cell (springs = "fitted-stable"'s term).
  Model<2> stable = volume;
  set_cell_shear(stable.net.volume, 5.0e4 / (2 * 1.45), kStableCellShear, 0.001, 0.05);
  // And averaged per node (springs = "nodal-volume": its force pass's scratch is the term's own).
  Model<2> nodal = volume;
  make_nodal_volumes(nodal.net.volume, nodal.net.num_nodes());
  for (const Model<2>* m : {&volume, static_cast<const Model<2>*>(&stable), static_cast<const Model<2>*>(&nodal)})
    for (const Case& c : {Case{"explicit", ""}, Case{"filtered", "full"}, Case{"filtered", "neighbors"},
                          Case{"implicit-euler", "", "direct"}, Case{"implicit-euler", "", "cg"}}) {
      const Model<2>& model = *m;
      IntegratorOptions o;
      o.kind = c.kind;
      o.filter = c.filter;
      o.linear_solver = c.linear_solver;
      o.dt = o.kind == "explicit" ? 1e-6 : 1e-3;
      auto integ = make_integrator(model, o);
      State<2> s = initial_state(model);
      integ->step(s); // warm up
      g_allocations = 0;
      g_counting = true;
      for (int k = 0; k < 50; ++k) integ->step(s);
      g_counting = false;
      EXPECT_EQ(g_allocations, 0) << c << (model.net.volume.has_shear() ? " with the shear part" : "")
                                  << (model.net.volume.nodal() ? " per node" : "");
    }
}

TEST(NoAllocation, MultigridFilterAllocatesNothing) {
  // 451 nodes: a hierarchy of three levels (the small plate above has none, as the filter
  // solves meshes below 64 free nodes directly).
  EXPECT_EQ(filtered_step_allocations(test::model_from(test::pulled_plate(40, 10, "")), "multigrid"), 0);
}

TEST(NoAllocation, TensorMultigridFilterAllocatesNothingWhileItsCoverMoves) {
  // The block V-cycle (three levels on 451 nodes) and its refresh when the pull's shear moves
  // the transverse cover (the Galerkin products into their patterns, the coarsest factor).
  const Model<2> model = test::model_from(test::pulled_plate(40, 10, ""));
  EXPECT_EQ(filtered_step_allocations(model, "tensor-multigrid"), 0);
}

TEST(NoAllocation, TensorFilterRelinearisationAllocatesNothing) {
  // Past its trusted distortion the tensor filter linearises again at the current shape
  // within a step: the blocks written into H's values, the factor (or the V-cycle) refreshed.
  const Model<2> model = test::model_from(test::pulled_plate(40, 10, ""));
  Nodal<2> u(2, model.num_nodes());
  for (int i = 0; i < model.num_nodes(); ++i) u.col(i) = Vec<2>(0.4 * model.net.rest(0, i), 0.1 * model.net.rest(0, i));
  for (const bool multigrid : {false, true}) {
    TensorFilter<2> filter(model, 1e-2, multigrid);
    filter.prepare(Nodal<2>::Zero(2, model.num_nodes()));
    g_allocations = 0;
    g_counting = true;
    filter.relinearize(u);
    filter.prepare(u);
    g_counting = false;
    EXPECT_EQ(g_allocations, 0) << (multigrid ? "tensor-multigrid" : "tensor");
    EXPECT_EQ(filter.relinearizations(), 1);
  }
}

TEST(NoAllocation, FreeBodyMomentumCorrectionAllocatesNothing) {
  const Model<2> model = test::model_from(test::plate_scene(8, 2, "[initial]\nangular_velocity = 1.0\n"));
  EXPECT_EQ(filtered_step_allocations(model, "neighbors"), 0);
}

TEST(NoAllocation, ServoContactAndShapingAllocateNothing) {
  // What a servo cycle calls: the proxy updates in 2D and 3D (outside, contact onset, deep in
  // contact), the AABB tree following a deformed body (refits within the margin and full
  // builds beyond it), and the force shaper.
  const Mesh2 plate = generate_rectangle({0.02, 0.02}, {4, 4});
  BoundaryContact c2(plate);
  const Mesh3 box = generate_box({0.02, 0.02, 0.02}, {3, 3, 3});
  SurfaceTree tree(box);
  SurfaceContact c3(tree);
  // With a tool tip of 8 mm (footprint.hh): wider than a facet, in 2D and 3D.
  TipFootprint<2> tip2(c2.facets(), plate.points, 0.008, 5e4, 0.3, 0.001);
  TipFootprint<3> tip3(tree.facets(), box.points, 0.008, 5e4, 0.3);
  ContactResult<2> last2;
  ContactResult<3> last3;
  int footprint_nodes = 0;
  BasicForceShaper<3> shaper({4.0, 0.5, 0.03, 0.01});
  Nodal<3> x = box.points;
  // The handle goes down in 1 mm steps from 5 mm above the top face to 14 mm into the box,
  // and lands exactly on the face on the way (where an exact-predicate kernel would fall back
  // to allocating GMP numbers).
  const auto cycle = [&](int k) {
    const double y = 0.025 - 0.001 * (k % 20);
    const auto r2 = hold_tip(c2, last2, tip2, Eigen::Vector2d(0.01, y), plate.points);
    x.row(1) = box.points.row(1) * (1.0 - 0.1 * (k % 7)); // squeezed by up to 12 mm: beyond the tree's margin
    tree.rebuild(x);
    const auto r = hold_tip(c3, last3, tip3, Eigen::Vector3d(0.01, y, 0.01), x);
    footprint_nodes = std::max({footprint_nodes, r2.footprint.count, r.footprint.count});
    shaper.shape(r.proxy - Eigen::Vector3d(0.01, y, 0.01), 1e-3 * k, 1e-3 * k, true);
  };
  cycle(0);
  const long builds = tree.builds();
  g_allocations = 0;
  g_counting = true;
  for (int k = 1; k < 60; ++k) cycle(k);
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
  EXPECT_GT(tree.builds(), builds) << "the squeeze exceeds the margin: full builds were exercised";
  EXPECT_GT(footprint_nodes, 3) << "the tips' footprints covered more than one facet";
}

TEST(NoAllocation, ServoCycleWithALocalModelAllocatesNothing) {
  // What a multirate servo cycle adds (local_model.hh): the proxy moved by the model (a shift
  // into the tip's contact), the coupling solved against the model, the record of the cycle
  // that the next physics step's force comes from (ForceHistory, applied_force).
  const Mesh3 box = generate_box({0.02, 0.02, 0.02}, {3, 3, 3});
  SurfaceTree tree(box);
  SurfaceContact c3(tree);
  TipFootprint<3> tip3(tree.facets(), box.points, 0.008, 5e4, 0.3);
  ContactResult<3> last3;
  LocalModel<3> model;
  model.valid = true;
  model.compliance = 2e-3 * Eigen::Matrix3d::Identity();
  model.applied = Eigen::Vector3d(0, -0.5, 0);
  ForceHistory<3> history;
  Nodal<3> v = Nodal<3>::Constant(3, box.points.cols(), 1e-3);
  double sum = 0;
  const auto cycle = [&](int k) {
    const Eigen::Vector3d h(0.01, 0.025 - 0.001 * (k % 20), 0.01);
    Eigen::Vector3d shift = model.compliance * model.applied;
    for (int p = 0; p < last3.footprint.count; ++p)
      shift += 1e-3 * last3.footprint.weight[static_cast<std::size_t>(p)] *
               v.col(last3.footprint.node[static_cast<std::size_t>(p)]);
    auto r = hold_tip(c3, last3, tip3, Eigen::Vector3d(h - shift), box.points);
    r.proxy += shift;
    const Eigen::Vector3d f = solve_against_local_model<3>(400.0 * (r.proxy - h), r.proxy - h, 400.0, model);
    history.sum -= f;
    history.proxy_sum += r.proxy;
    ++history.cycles;
    sum += applied_force<3>(history, r.proxy, 400.0).norm();
  };
  cycle(0);
  g_allocations = 0;
  g_counting = true;
  for (int k = 1; k < 60; ++k) cycle(k);
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
  EXPECT_GT(sum, 0.0) << "the cycles pressed";
}

} // namespace
} // namespace vtb

#ifdef VTB_HAVE_LIVE_SIM
namespace vtb {
namespace {

/// The Python module's step (vtb.Simulation.step: LiveSim::steps) with forces set from outside
/// between steps, with their couplings' stiffness and damping, and a pull: nothing allocated,
/// for each stepper the module offers.
TEST(NoAllocation, InteractiveStepsWithExternalForcesAllocateNothing) {
  for (const char* solver : {"filtered", "implicit-euler", "explicit"}) {
    const Scene scene = parse_scene(test::pulled_plate(12, 3, "[solver]\nsprings = \"lloyd\"\n"), "test.toml", ".");
    SimControls c;
    c.solver = solver;
    c.springs = "lloyd";
    c.dt = std::string(solver) == "explicit" ? 1e-6 : 1e-3;
    LiveSim<2> sim(scene, std::get<Mesh2>(load_mesh(scene)), c);
    sim.add_pull(5, Vec<2>(0.1, 0.0));
    sim.steps(2); // warm up
    g_allocations = 0;
    g_counting = true;
    for (int k = 0; k < 20; ++k) {
      sim.external_force().col(30) = Vec<2>(0.0, -0.01 * k); // what a Python controller writes
      sim.external_stiffness()[30] = 50.0;
      sim.external_damping()[30] = 0.5;
      sim.steps(1);
    }
    g_counting = false;
    EXPECT_EQ(g_allocations, 0) << solver;
    EXPECT_TRUE(sim.failure().empty()) << solver << ": " << sim.failure();
  }
}

} // namespace
} // namespace vtb
#endif // VTB_HAVE_LIVE_SIM
