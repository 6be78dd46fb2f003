#pragma once
/// \file
/// A user's closed surface (OFF, STL ASCII or binary, OBJ, PLY), read and checked before CGAL
/// meshes its inside (cgal_generate.hh, mesh_surface). A surface file is untrusted input: the
/// declared counts are checked against the file's size before a reader allocates, the reader
/// runs in a child process (isolated.hh), and what is not a closed, manifold, non-degenerate,
/// non-self-intersecting surface is refused with one line naming the file and the fault.

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vtb {

/// A checked closed triangle surface: faces consistently oriented, normals outward.
struct Surface {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<int, 3>> triangles;
  int reoriented = 0; ///< faces whose orientation the reader reversed (reported as a warning)
};

/// The formats read_surface takes, by file extension (lower case).
inline constexpr std::array<std::string_view, 4> kSurfaceFormats{".off", ".stl", ".obj", ".ply"};

/// Refuses, before any reader allocates, a file whose declared counts (OFF's and PLY's
/// element counts, binary STL's triangle count) do not fit in its size. `format` is one of
/// kSurfaceFormats. Throws InputError "SRC: ...".
void prescan_surface(std::string_view content, std::string_view format, const std::string& src);

/// Parses and checks a surface in process: the pre-scan, CGAL's reader, then the checks (at
/// least one face, indices in range, finite coordinates, no degenerate face, every edge shared
/// by exactly two faces, no vertex joining sheets that touch only there, no self-intersection);
/// faces oriented consistently and outward (counted in `reoriented`); polygons triangulated.
/// Coordinates are multiplied by `scale`. Throws InputError "SRC: ..." naming the fault.
Surface parse_surface(std::string_view content, std::string_view format, const std::string& src, double scale = 1);

/// The checks and orientation of parse_surface on a polygon soup (what a reader gave). Throws
/// InputError "SRC: ...".
Surface checked_surface(std::vector<Eigen::Vector3d> points, std::vector<std::vector<std::size_t>> polygons,
                        const std::string& src, double scale = 1);

/// Reads FILE (by its extension) through parse_surface in an isolated child process (8 s limit);
/// prints a warning on stderr when faces were reoriented.
Surface read_surface(const std::filesystem::path& file, double scale = 1);

} // namespace vtb
