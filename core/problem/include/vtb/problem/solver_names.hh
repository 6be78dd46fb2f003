#pragma once
/// \file
/// The solver names, each written once (the registry, solver_registry.hh, describes them).

#include <array>

namespace vtb::solvers {

inline constexpr const char* kExplicit = "explicit";
inline constexpr const char* kFiltered = "filtered"; ///< the scene's [solver].filter
inline constexpr const char* kFilteredFull = "filtered-full";
inline constexpr const char* kFilteredNeighbors = "filtered-neighbors";
inline constexpr const char* kFilteredTensor = "filtered-tensor";
inline constexpr const char* kFilteredMultigrid = "filtered-multigrid";
inline constexpr const char* kFilteredTensorMultigrid = "filtered-tensor-multigrid";
inline constexpr const char* kImplicitEuler = "implicit-euler";
inline constexpr const char* kCvode = "cvode";
inline constexpr const char* kFem = "fem";
/// A reference of `vtb compare` only: the FEM with the scene's own [solver] degree and
/// refinements (P1 on the mesh by default), beside `fem`, which there is the continuum.
inline constexpr const char* kFemMesh = "fem-mesh";
inline constexpr const char* kBullet = "bullet"; ///< a peer library (the harness runs it)

/// The filters of `filtered` ([solver].filter).
inline constexpr const char* kFilterFull = "full";
inline constexpr const char* kFilterNeighbors = "neighbors";
inline constexpr const char* kFilterTensor = "tensor";
inline constexpr const char* kFilterMultigrid = "multigrid";              ///< full, H^-1 by one V-cycle
inline constexpr const char* kFilterTensorMultigrid = "tensor-multigrid"; ///< tensor, H^-1 by one block V-cycle
/// The default: the integrator picks one of the filters for the model (chosen_filter, integrator.hh).
inline constexpr const char* kFilterAuto = "auto";
/// Every filter, in the order the integrator's check and the study list them.
inline constexpr std::array<const char*, 5> kFilters = {kFilterNeighbors, kFilterFull, kFilterTensor, kFilterMultigrid,
                                                        kFilterTensorMultigrid};
/// What [solver].filter accepts and the viewer offers: auto, then every filter.
inline constexpr std::array<const char*, 6> kFilterChoices = {kFilterAuto,   kFilterNeighbors, kFilterFull,
                                                              kFilterTensor, kFilterMultigrid, kFilterTensorMultigrid};

} // namespace vtb::solvers
