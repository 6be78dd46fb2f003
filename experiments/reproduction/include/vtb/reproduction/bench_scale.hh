#pragma once
/// \file
/// `vtb bench scale`: step time, precompute, memory and error against the FEM of the spring
/// solvers (filtered-full, filtered-multigrid, implicit-euler) over a 2D rectangle, a 3D box
/// and a CGAL slab ladder (the reproduction's scaling.csv), and the fitted exponent of each
/// cost against the node count (scaling_fit.csv).

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace vtb::reproduction {

/// Writes OUT/scaling.csv and OUT/scaling_fit.csv (family, dim, solver, nodes_min, nodes_max,
/// step_exponent, precompute_exponent, heap_exponent: least-squares slopes of log cost against
/// log nodes) and OUT/spring_fit.csv (the spring fit's wall time, steps and held-out error on
/// CGAL slabs of 1k to 10k nodes) and prints both to `table`.
void bench_scale(const std::filesystem::path& out, bool quick, std::ostream* progress, std::ostream& table);

/// spring_fit.csv's text: the spring fit (springs = "fitted", no cache, the default options
/// on the scene's supports) on CGAL Mesh_3 slabs 0.2 x 0.05 x 0.05 m clamped at one end, of
/// about `slabs` nodes each: nodes, springs, wall time, the Levenberg-Marquardt steps, the
/// held-out error and the constants the guard kept. A build without CGAL's meshers writes
/// the header alone.
std::string fit_ladder(const std::vector<int>& slabs, std::ostream* log);

/// The fit of scaling.csv in `dir`, as scaling_fit.csv's text.
std::string scaling_fit(const std::filesystem::path& dir);

} // namespace vtb::reproduction
