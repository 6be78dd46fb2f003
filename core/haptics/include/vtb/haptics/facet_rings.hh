#pragma once
/// \file
/// The boundary facets around each facet: those sharing a node with it, as CSR. The proxy's
/// walk (contact3d.hh) and the tool tip's footprint search (footprint.hh) step over them.

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace vtb {

/// ptr[f] .. ptr[f + 1] index ring: the facets other than f that share a node with f, sorted.
template <std::size_t n>
void facet_rings(const std::vector<std::array<int, n>>& facets, int nodes, std::vector<int>& ptr,
                 std::vector<int>& ring) {
  std::vector<std::vector<int>> around(static_cast<std::size_t>(nodes)); // facets at each node
  for (std::size_t f = 0; f < facets.size(); ++f)
    for (int v : facets[f]) around[static_cast<std::size_t>(v)].push_back(static_cast<int>(f));
  ptr.assign(1, 0);
  ring.clear();
  std::vector<int> one;
  for (std::size_t f = 0; f < facets.size(); ++f) {
    one.clear();
    for (int v : facets[f])
      for (int g : around[static_cast<std::size_t>(v)])
        if (g != static_cast<int>(f)) one.push_back(g);
    std::sort(one.begin(), one.end());
    one.erase(std::unique(one.begin(), one.end()), one.end());
    ring.insert(ring.end(), one.begin(), one.end());
    ptr.push_back(static_cast<int>(ring.size()));
  }
}

} // namespace vtb
