#pragma once
/// \file
/// The fitted springs' cache: the fit depends only on the mesh, the Poisson ratio and the
/// scene's supports (never on its loads; the constants scale with E t), so they are kept on
/// disk per mesh, Poisson ratio and supports, and a later run on the same ones, at any
/// stiffness, reads them instead of fitting again (0.2 s at 517 nodes in 2D, seconds in 3D). Best effort: a cache that
/// cannot be read or written is passed over, never an error.

#include "vtb/meshes/mesh.hh"
#include "vtb/springs/fitted_springs.hh"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace vtb {

/// Where the cache lives: $VTB_CACHE_DIR, else $XDG_CACHE_HOME/vtb, else $HOME/.cache/vtb;
/// empty (no cache) when VTB_CACHE_DIR is set but empty, or none of them is set.
std::filesystem::path fit_cache_dir();

/// The version of the code that computes a fit: the SHA-256 of its sources (the fit, its
/// training, the priors, the network, the continuum's answers), 64 hex digits. A cached fit
/// holds it and is read back only by the same version.
std::string fit_code_version();

/// What a fit, fresh or cached, returned besides its constants (fitted_springs.hh FitReport).
struct CachedFit {
  bool hit = false;      ///< the constants came from the cache
  std::string chosen;    ///< "fitted", or the prior the guard kept ("lloyd", "van-gelder")
  double validation = 0; ///< the chosen constants' relative error on the held-out modes
};

/// fitted_stiffness(mesh, E, nu, t) with the default options and these supports (sorted
/// nodes), through the cache: the fit at unit E t, scaled by E t (the fit is equivariant in
/// them, so this equals the direct fit to rounding), kept in the file fitted-<key>.bin, key a
/// 64-bit FNV-1a hash of the format version, the points, the cells, nu, the supports, the
/// fit's options and its target's key (FitTarget: the continuum or P1). A file of the wrong
/// size or header, or written by another fit_code_version(), is refitted and replaced
/// (atomically). With cell_stiffness the fit with a volume term (FitOptions::volume; its own
/// key): the cells' constants go there, in make_cell_volumes' order; `cell_shear` is
/// FitOptions::cell_shear (in the key where it is not 0); `nodal`: FitOptions::nodal
/// (cell_stiffness then holds the nodes' k_n).
template <int dim>
Eigen::VectorXd cached_fitted_stiffness(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio,
                                        double thickness, const std::vector<int>& supports = {},
                                        CachedFit* info = nullptr, const FitProgress& progress = {},
                                        const FitTarget& target = {}, Eigen::VectorXd* cell_stiffness = nullptr,
                                        double cell_shear = 0, bool nodal = false);

} // namespace vtb
