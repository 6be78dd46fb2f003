#pragma once
/// \file
/// Every solver vtb runs, registered once: its name, a one-line description, what it runs
/// ([solver].kind and filter), the scene keys it reads, and what it is. The CLI's help, the
/// scene parser's validation, the harness, the reproduction and the viewer read this table;
/// no solver name is written anywhere else (use the constants below).
///
/// The factories: a spring solver is made by make_integrator (or CVODE's own loop in
/// simulate) from `integrator_options(entry, [solver])`; `fem` by reference_fem's simulate,
/// which the harness's run_solver dispatches to. vtb::core cannot name reference_fem, so the
/// dispatch sits one layer up and a test checks that every entry runs.

#include "vtb/problem/scene.hh"
#include "vtb/problem/solver_names.hh"

#include <string>
#include <string_view>
#include <vector>

namespace vtb::solvers {

struct Entry {
  const char* name;
  const char* description; ///< one line, for --help and the docs
  const char* kind;        ///< the [solver].kind it runs
  const char* filter;      ///< "" or the filter it fixes
  const char* keys;        ///< the [solver] keys it reads, besides kind
  bool scene_kind;         ///< a value [solver].kind accepts
  bool springs;            ///< integrates the spring network (fem does not)
  bool fixed_step;         ///< runs at a given dt (cvode chooses its own steps)
  bool interactive;        ///< vtb view can switch to it while running
};

inline constexpr Entry kEntries[] = {
    {kExplicit, "symplectic Euler; stable below the Courant limit only", kExplicit, "", "dt, strain_limit", true, true,
     true, true},
    {kFiltered,
     "the paper's filtered implicit scheme with the scene's filter (auto: tensor, tensor-multigrid from 1,000 free "
     "nodes in 3D, multigrid from 12,000)",
     kFiltered, "", "dt, filter, momentum_correction, strain_limit", true, true, true, true},
    {kFilteredFull, "the filtered scheme with the full inverse W (stable at any dt)", kFiltered, kFilterFull,
     "dt, momentum_correction, strain_limit", false, true, true, false},
    {kFilteredNeighbors, "the filtered scheme truncated to mesh neighbours (the paper's)", kFiltered, kFilterNeighbors,
     "dt, momentum_correction, strain_limit", false, true, true, false},
    {kFilteredTensor, "the filtered scheme with the rest Jacobian's blocks and stiffness warping (no lag)", kFiltered,
     kFilterTensor, "dt, momentum_correction, strain_limit", false, true, true, false},
    {kFilteredMultigrid, "the full filter with H^-1 applied by one symmetric multigrid V-cycle (large 3D meshes)",
     kFiltered, kFilterMultigrid, "dt, momentum_correction, strain_limit", false, true, true, false},
    {kFilteredTensorMultigrid,
     "the tensor filter with H_t^-1 applied by one symmetric block V-cycle with rigid-mode coarse spaces (large 3D "
     "meshes)",
     kFiltered, kFilterTensorMultigrid, "dt, momentum_correction, strain_limit", false, true, true, false},
    {kImplicitEuler,
     "linearised backward Euler with the spring Jacobian (sparse LDL^T, or warm-started CG with block Jacobi or the "
     "multigrid V-cycle)",
     kImplicitEuler, "", "dt, strain_limit, linear_solver, cg_tolerance", true, true, true, true},
    {kCvode, "SUNDIALS CVODE (BDF, Newton, KLU) on the same ODE, adaptive steps", kCvode, "", "rtol, atol", true, true,
     false, false},
    {kBullet,
     "Bullet 3.24's deformable world: uniform springs and dashpots on the mesh edges, explicit elastic and implicit "
     "damping forces, "
     "k fitted to the FEM's static energy (a peer)",
     kBullet, "", "dt", false, true, true, false},
    {kFem, "deal.II Kelvin-Voigt finite elements on the same mesh (the continuum reference)", kFem, "",
     "dt, degree, refinements, scheme, static, static_path, kinematics", true, false, true, false},
};

/// Filters for names() and list().
inline bool is_scene_kind(const Entry& e) {
  return e.scene_kind;
}
inline bool is_stepper(const Entry& e) {
  return e.interactive;
} ///< one fixed step at a time (view, haptics)
inline bool is_spring(const Entry& e) {
  return e.springs;
}

/// The entry of `name`; InputError naming the nearest known name otherwise ("where" prefixes
/// the message, e.g. "--solvers").
const Entry& find(std::string_view name, std::string_view where = "solver");

/// A registry name as a [solver].kind and filter: the entry's kind, and its filter when it fixes
/// one (filtered-tensor: kind filtered, filter tensor); `filter` is left as it is otherwise.
/// InputError as find() for an unknown name.
void select(std::string_view name, std::string_view where, std::string& kind, std::string& filter);

/// The names of the entries that satisfy `keep` (all by default), in table order.
std::vector<std::string> names(bool (*keep)(const Entry&) = nullptr);

/// "a, b, c or d": the names for a message or --help.
std::string list(bool (*keep)(const Entry&) = nullptr);

} // namespace vtb::solvers
