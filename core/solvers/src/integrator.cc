#include "vtb/solvers/integrator.hh"
#include "vtb/problem/overrides.hh"
#include "vtb/problem/solver_registry.hh"

#include "vtb/solvers/explicit_euler.hh"
#include "vtb/solvers/filtered.hh"
#include "vtb/solvers/implicit_euler.hh"
#include "vtb/solvers/implicit_euler_cg.hh"

namespace vtb {

template <int dim> State<dim> initial_state(const Model<dim>& model) {
  State<dim> s;
  s.u = Nodal<dim>::Zero(dim, model.num_nodes());
  s.v = model.initial_velocity;
  model.apply_constraints(0.0, s.u, s.v);
  return s;
}

template <int dim> std::string chosen_filter(const Model<dim>& model, const std::string& filter) {
  if (filter != solvers::kFilterAuto) return filter;
  const std::size_t free = model.free_nodes.size();
  // The lag-free tensor filter: the full filter's extra mass costs 7-22x its transient error in
  // 2D, 80-99 % on a twisted bar, 30 % on a loaded 2k slab and 16 % on the 10k slab in 3D
  // (docs/method.md), at 2-3x its step in 2D and 4-9x in 3D; in 3D by its factor on small
  // meshes and its block V-cycle from kTensorCycleFreeNodes3D (on the 10k slab 1.9x cheaper
  // than implicit Euler, as accurate, 188 MB peak). Beyond the sizes measured, the scalar
  // V-cycle (a ninth of the cost, and the lag).
  if (dim == 3 && free >= kScalarCycleFreeNodes3D) return solvers::kFilterMultigrid;
  // The tensor filter has no cell blocks for the volume term (docs/method.md): its scalar
  // counterparts at the same sizes.
  const bool cells = !model.net.volume.empty();
  if (dim == 3 && free >= kTensorCycleFreeNodes3D)
    return cells ? solvers::kFilterMultigrid : solvers::kFilterTensorMultigrid;
  return cells ? solvers::kFilterFull : solvers::kFilterTensor;
}

template <int dim>
std::unique_ptr<Integrator<dim>> make_integrator(const Model<dim>& model, const IntegratorOptions& o) {
  checked_dt(o.dt);
  if (o.kind == solvers::kExplicit) return std::make_unique<ExplicitEuler<dim>>(model, o.dt);
  if (o.kind == solvers::kFiltered) return std::make_unique<FilteredImplicit<dim>>(model, o);
  if (o.kind == solvers::kImplicitEuler) {
    // auto: the factor's fill grows like n log n in 2D but n^(4/3) in 3D (nested dissection),
    // so the refactorised LDL^T wins in 2D (517 nodes: 0.30 ms against CG's 1.46 ms) and CG
    // in 3D (458 nodes: 1.15 ms against 1.62 ms; 9,864 nodes: 105 ms against 2.7 s). From
    // 4,000 free nodes in 3D the CG is preconditioned by the multigrid V-cycle: 1.8x to 2.9x
    // faster at 10k nodes, but up to 2.3x slower on structured boxes of 1,225 nodes
    // (bench scale; docs/performance.md).
    if (o.linear_solver != "auto" && o.linear_solver != "direct" && o.linear_solver != "cg" &&
        o.linear_solver != "cg-multigrid")
      throw InputError("[solver].linear_solver = \"" + o.linear_solver +
                       "\": must be auto, direct, cg or cg-multigrid");
    const bool large = model.free_nodes.size() >= kLargeFreeNodes3D;
    if (o.linear_solver == "cg-multigrid" || (o.linear_solver == "auto" && dim == 3 && large))
      return std::make_unique<ImplicitEulerCG<dim>>(model, o.dt, o.cg_tolerance, true);
    if (o.linear_solver == "cg" || (o.linear_solver == "auto" && dim == 3))
      return std::make_unique<ImplicitEulerCG<dim>>(model, o.dt, o.cg_tolerance);
    return std::make_unique<ImplicitEuler<dim>>(model, o.dt);
  }
  if (o.kind == solvers::kCvode || o.kind == solvers::kFem)
    throw InputError("[solver].kind = \"" + o.kind +
                     "\": not a fixed-step integrator (it runs whole with vtb run, compare and study, not one step at "
                     "a time as view and haptics need); a stepper is one of " +
                     solvers::list(solvers::is_stepper));
  throw InputError("[solver].kind = \"" + o.kind + "\": must be " + solvers::list(solvers::is_stepper));
}

template std::string chosen_filter<2>(const Model<2>&, const std::string&);
template std::string chosen_filter<3>(const Model<3>&, const std::string&);
template State<2> initial_state<2>(const Model<2>&);
template State<3> initial_state<3>(const Model<3>&);
template std::unique_ptr<Integrator<2>> make_integrator<2>(const Model<2>&, const IntegratorOptions&);
template std::unique_ptr<Integrator<3>> make_integrator<3>(const Model<3>&, const IntegratorOptions&);

} // namespace vtb
