#pragma once
/// \file
/// The fitted springs' cache: the fit depends only on the mesh and the material (never on a
/// scene's loads or supports), so its constants are kept on disk per mesh and material and a
/// later run on the same ones reads them instead of fitting again (0.2 s at 517 nodes in 2D,
/// 1 s at 458 in 3D, 26 s at 1,917). Best effort: a cache that cannot be read or written is
/// passed over, never an error.

#include "vtb/meshes/mesh.hh"

#include <Eigen/Core>

#include <filesystem>

namespace vtb {

/// Where the cache lives: $VTB_CACHE_DIR, else $XDG_CACHE_HOME/vtb, else $HOME/.cache/vtb;
/// empty (no cache) when VTB_CACHE_DIR is set but empty, or none of them is set.
std::filesystem::path fit_cache_dir();

/// fitted_stiffness(mesh, E, nu, t) with the default options, through the cache: the file
/// fitted-<key>.bin, key a 64-bit FNV-1a hash of the format version, the points, the cells, the
/// material and the fit's options. A file of the wrong size or header is refitted and replaced
/// (atomically). `hit` (optional) says whether the constants came from the cache.
template <int dim>
Eigen::VectorXd cached_fitted_stiffness(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio,
                                        double thickness, bool* hit = nullptr);

} // namespace vtb
