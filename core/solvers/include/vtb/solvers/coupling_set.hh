#pragma once
/// \file
/// The couplings from outside (a user's pull, a haptic contact, a tool tip's footprint) as the
/// implicit filters take them into their solve: units, each a set of nodes with weights w
/// (sum 1) sharing one coefficient c = dt^2 k + dt b, whose part of the step's system is
/// c w w^T on every axis. A node with no group is a unit of its own (w = 1: c at its diagonal,
/// a viewer's drag); the nodes of a group (State::applied_group) are one unit, w_i = c_i / sum c.
/// A tip spreading its coupling's force over a footprint by weights w has exactly this
/// Jacobian, where a per-node diagonal is only a bound. The solvers apply it through Woodbury's
/// identity with one column per unit and axis, so a footprint of 40 nodes costs dim solves
/// when it changes, not 40 dim. Nothing is allocated after construction.

#include "vtb/solvers/integrator.hh"

#include <array>
#include <cmath>
#include <vector>

namespace vtb {

template <int dim> class CouplingSet {
public:
  static constexpr int kMaxUnits = 16; ///< units solved implicitly at most; more apply their force alone
  static constexpr int kMaxNodes = 64; ///< nodes per unit at most; more apply their force alone

  /// `slot_of_node`: each node's place in the consumer's system (a free index, a factor row;
  /// -1: not in it, a fixed node).
  explicit CouplingSet(std::vector<int> slot_of_node) : m_slot_of_node(std::move(slot_of_node)) {}

  /// The state's couplings at step dt (applied_stiffness, applied_damping, applied_group).
  /// Returns whether the units' nodes or weights changed since the last call (what Z = H^-1 U
  /// depends on); a change of the coefficients alone is not one.
  bool gather(const State<dim>& s, double dt) {
    return set(s.applied_stiffness, s.applied_damping, s.applied_group, dt);
  }

  /// The same from per-node stiffness k and damping b (either may be empty) and groups (-1 or
  /// empty: none): c_i = dt^2 k_i + dt b_i.
  bool set(const Eigen::VectorXd& k, const Eigen::VectorXd& b, const Eigen::VectorXi& group, double dt) {
    // The units are made in the other of two buffers and compared with the current one, which
    // spares the step a copy of both (16 units of 64 nodes: 16 KB).
    const auto n = static_cast<Eigen::Index>(m_slot_of_node.size());
    const std::array<Unit, kMaxUnits>& old = m_buffer[static_cast<std::size_t>(m_current)];
    std::array<Unit, kMaxUnits>& units = m_buffer[static_cast<std::size_t>(1 - m_current)];
    int count = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double ki = k.size() == n ? k[i] : 0.0;
      const double c = dt * dt * ki + dt * (b.size() == n ? b[i] : 0.0);
      const int slot = m_slot_of_node[static_cast<std::size_t>(i)];
      if (slot < 0 || !(c > 0) || !std::isfinite(c)) continue;
      const int g = group.size() == n ? group[i] : -1;
      int u = 0;
      while (u < count && !(g >= 0 && units[static_cast<std::size_t>(u)].group == g)) ++u;
      if (u == count) {
        if (count == kMaxUnits) continue;
        Unit& fresh = units[static_cast<std::size_t>(count++)];
        fresh.group = g, fresh.size = 0, fresh.c = 0.0, fresh.k = 0.0;
      }
      Unit& unit = units[static_cast<std::size_t>(u)];
      if (unit.size == kMaxNodes) continue;
      unit.node[static_cast<std::size_t>(unit.size)] = static_cast<int>(i);
      unit.slot[static_cast<std::size_t>(unit.size)] = slot;
      unit.weight[static_cast<std::size_t>(unit.size++)] = c;
      unit.c += c;
      unit.k += ki;
    }
    bool changed = count != m_count;
    for (int u = 0; u < count; ++u) {
      Unit& unit = units[static_cast<std::size_t>(u)];
      for (int p = 0; p < unit.size; ++p) unit.weight[static_cast<std::size_t>(p)] /= unit.c;
      if (changed) continue;
      const Unit& o = old[static_cast<std::size_t>(u)];
      changed = o.size != unit.size;
      for (int p = 0; p < unit.size && !changed; ++p)
        changed = o.slot[static_cast<std::size_t>(p)] != unit.slot[static_cast<std::size_t>(p)] ||
                  o.weight[static_cast<std::size_t>(p)] != unit.weight[static_cast<std::size_t>(p)];
    }
    m_current = 1 - m_current;
    m_count = count;
    m_version += changed;
    return changed;
  }

  /// Counts the calls of set() that changed the units' nodes or weights.
  long version() const { return m_version; }

  int units() const { return m_count; }
  /// The unit that holds coupling group g (State::applied_group), -1 if none.
  int unit_of_group(int g) const {
    for (int u = 0; u < m_count; ++u)
      if (unit(u).group == g) return u;
    return -1;
  }
  int size(int u) const { return unit(u).size; }
  int node(int u, int p) const { return unit(u).node[static_cast<std::size_t>(p)]; }
  int slot(int u, int p) const { return unit(u).slot[static_cast<std::size_t>(p)]; }
  double weight(int u, int p) const { return unit(u).weight[static_cast<std::size_t>(p)]; }
  double coefficient(int u) const { return unit(u).c; } ///< dt^2 k + dt b of the unit

  /// w . x over unit u's nodes (x by node).
  Vec<dim> weighted(int u, const Nodal<dim>& x) const {
    Vec<dim> sum = Vec<dim>::Zero();
    for (int p = 0; p < size(u); ++p) sum += weight(u, p) * x.col(node(u, p));
    return sum;
  }

  /// The couplings' force over the step that the implicit system expects on its right-hand
  /// side (as a spring's dt K v): force_i -= dt k w_i (w . v), by node.
  void add_force_correction(const Nodal<dim>& v, double dt, Nodal<dim>& force) const {
    for (int u = 0; u < m_count; ++u) {
      const Vec<dim> wv = dt * unit(u).k * weighted(u, v);
      for (int p = 0; p < size(u); ++p) force.col(node(u, p)) -= weight(u, p) * wv;
    }
  }

  /// y -= (sum over units of c w w^T) x, by node; returns x . (that) x.
  double subtract_product(const Nodal<dim>& x, Nodal<dim>& y) const {
    double energy = 0;
    for (int u = 0; u < m_count; ++u) {
      const Vec<dim> wx = coefficient(u) * weighted(u, x);
      for (int p = 0; p < size(u); ++p) y.col(node(u, p)) -= weight(u, p) * wx;
      energy += wx.squaredNorm() / coefficient(u);
    }
    return energy;
  }

  /// x . (sum over units of c w w^T) x, by node.
  double energy(const Nodal<dim>& x) const {
    double e = 0;
    for (int u = 0; u < m_count; ++u) e += coefficient(u) * weighted(u, x).squaredNorm();
    return e;
  }

private:
  struct Unit {
    int group = -1, size = 0;
    double c = 0, k = 0; ///< the unit's dt^2 k + dt b and its k
    std::array<int, kMaxNodes> node{}, slot{};
    std::array<double, kMaxNodes> weight{};
  };
  const Unit& unit(int u) const { return m_buffer[static_cast<std::size_t>(m_current)][static_cast<std::size_t>(u)]; }

  std::vector<int> m_slot_of_node;
  std::array<std::array<Unit, kMaxUnits>, 2> m_buffer{}; ///< the units now, and the next set()'s
  int m_current = 0;
  int m_count = 0;
  long m_version = 0;
};

} // namespace vtb
