#pragma once
// Internal to reference_fem: a solved level's displacement at its support points, found by
// position, so that the next uniform refinement's Newton starts from it (nested iteration,
// docs/fem.md "Nested iteration"). Uniform refinement of a simplex puts the fine vertices at
// the coarse P2 support points (vertices and edge midpoints), so a coarse P2 answer gives every
// fine vertex its value; a fine edge's midpoint takes the mean of its two ends.

#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

namespace vtb::fem {

template <int dim> class LevelAnswer {
public:
  /// `quantum`: the spacing of the position grid the points are filed on; points closer than it
  /// are one point (a millionth of the smallest edge is far below any mesh's spacing and far above
  /// the rounding of a midpoint computed two ways).
  explicit LevelAnswer(double quantum) : m_quantum(quantum) {}

  /// Component c of the displacement at p.
  void add(const dealii::Point<dim>& p, int c, double value) {
    m_points.push_back(p);
    m_comp.push_back(c);
    m_value.push_back(value);
  }

  /// Every rank's points on every rank, then filed by position.
  void gather(MPI_Comm comm) {
    int mpi = 0; // a plain run never initialises MPI (kelvin_voigt.cc's MpiScope)
    MPI_Initialized(&mpi);
    if (mpi && dealii::Utilities::MPI::n_mpi_processes(comm) > 1) {
      std::vector<double> mine;
      for (std::size_t k = 0; k < m_points.size(); ++k) {
        for (int a = 0; a < dim; ++a) mine.push_back(m_points[k][a]);
        mine.push_back(m_comp[k]);
        mine.push_back(m_value[k]);
      }
      m_points.clear(), m_comp.clear(), m_value.clear();
      for (const auto& part : dealii::Utilities::MPI::all_gather(comm, mine))
        for (std::size_t k = 0; k + dim + 2 <= part.size(); k += dim + 2) {
          dealii::Point<dim> p;
          for (int a = 0; a < dim; ++a) p[a] = part[k + static_cast<std::size_t>(a)];
          add(p, static_cast<int>(part[k + dim]), part[k + dim + 1]);
        }
    }
    m_index.clear();
    for (std::size_t k = 0; k < m_points.size(); ++k) m_index.emplace(key(m_points[k], m_comp[k]), k);
  }

  /// Component c of the displacement at p, if a point of this level lies within the quantum.
  std::optional<double> at(const dealii::Point<dim>& p, int c) const {
    // The grid cells around p's: a point near a cell's border may be filed in the next.
    std::array<std::int64_t, dim> base{};
    for (int a = 0; a < dim; ++a) base[a] = static_cast<std::int64_t>(std::floor(p[a] / m_quantum));
    for (int n = 0; n < ipow3(); ++n) {
      std::array<std::int64_t, dim> cell = base;
      for (int a = 0, m = n; a < dim; ++a, m /= 3) cell[a] += m % 3 - 1;
      const auto [first, last] = m_index.equal_range(hash(cell, c));
      for (auto it = first; it != last; ++it)
        if (m_comp[it->second] == c && m_points[it->second].distance(p) <= m_quantum) return m_value[it->second];
    }
    return std::nullopt;
  }

  std::size_t size() const { return m_points.size(); }

private:
  static constexpr int ipow3() { return dim == 2 ? 9 : 27; }
  std::uint64_t key(const dealii::Point<dim>& p, int c) const {
    std::array<std::int64_t, dim> cell{};
    for (int a = 0; a < dim; ++a) cell[a] = static_cast<std::int64_t>(std::floor(p[a] / m_quantum));
    return hash(cell, c);
  }
  static std::uint64_t hash(const std::array<std::int64_t, dim>& cell, int c) {
    std::uint64_t h = static_cast<std::uint64_t>(c) * 0x9E3779B97F4A7C15ull;
    for (const auto v : cell) h = (h ^ static_cast<std::uint64_t>(v)) * 0x100000001B3ull + 0x9E3779B97F4A7C15ull;
    return h;
  }

  double m_quantum;
  std::vector<dealii::Point<dim>> m_points;
  std::vector<int> m_comp;
  std::vector<double> m_value;
  std::unordered_multimap<std::uint64_t, std::size_t> m_index;
};

} // namespace vtb::fem
