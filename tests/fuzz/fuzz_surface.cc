// libFuzzer target for vtb's own surface hardening, in process (surface.hh). The first byte
// picks what the rest feeds: the pre-scan of declared counts for OFF, STL, OBJ or PLY text
// (bytes 0-3 mod 5), or (4 mod 5) a polygon soup for the checks and orientation that follow a
// reader (checked_surface: closed, manifold, degenerate, self-intersection, outward). The soup is
// a vertex count, integer coordinates in [-8, 7] (so that faces meet, touch and cross), then
// faces as a count and that many indices. CGAL's readers themselves run in a child process whose
// crashes become refusals (isolated.hh), as gmsh's do; this target found that CGAL's PLY reader
// takes a property before any element as an element's (now refused by the pre-scan), so they are
// not fuzzed here.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/surface.hh"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t pick = data[0] % 5;
  ++data;
  --size;
  try {
    if (pick < 4) {
      vtb::prescan_surface(std::string_view(reinterpret_cast<const char*>(data), size), vtb::kSurfaceFormats[pick],
                           "fuzz");
      return 0;
    }
    std::size_t at = 0;
    auto next = [&]() -> int { return at < size ? data[at++] : -1; };
    const int nv = next();
    if (nv < 0) return 0;
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < nv; ++i) {
      Eigen::Vector3d p;
      for (int d = 0; d < 3; ++d) {
        const int b = next();
        if (b < 0) return 0;
        p[d] = (b & 15) - 8;
      }
      points.push_back(p);
    }
    std::vector<std::vector<std::size_t>> faces;
    for (int n = next(); n >= 0; n = next()) {
      std::vector<std::size_t> f;
      for (int k = 0; k < (n & 7); ++k) {
        const int v = next();
        if (v < 0) break;
        f.push_back(static_cast<std::size_t>(v));
      }
      faces.push_back(std::move(f));
    }
    vtb::checked_surface(std::move(points), std::move(faces), "fuzz");
  } catch (const vtb::InputError&) {
  }
  return 0;
}
