#include "vtb/haptics/device.hh"

#include "vtb/base/input_error.hh"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace vtb {

Eigen::Vector2d HandScript::at(double t) const {
  if (waypoints.empty()) return Eigen::Vector2d::Zero();
  if (waypoints.size() == 1 || t <= 0) return waypoints.front();
  const double s = std::min(t / duration, 1.0) * static_cast<double>(waypoints.size() - 1);
  const auto k = std::min(static_cast<std::size_t>(s), waypoints.size() - 2);
  const double f = s - static_cast<double>(k);
  return (1 - f) * waypoints[k] + f * waypoints[k + 1];
}

SimulatedProCAT::SimulatedProCAT(const DeviceSpec& spec, HandScript hand, Physical physical)
    : m_spec(spec), m_hand(std::move(hand)), m_phys(physical),
      m_x(m_hand.at(0).cwiseMax(spec.workspace_min).cwiseMin(spec.workspace_max)), m_measured(m_x),
      m_velocity(physical.encoder) {
  m_velocity.add(m_t, m_measured);
}

void SimulatedProCAT::read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const {
  position = m_measured;
  velocity = m_velocity.velocity();
}

void SimulatedProCAT::command(const Eigen::Vector2d& force) {
  // The amplifier's own limit, keeping direction; a non-finite command renders nothing.
  if (!force.allFinite()) {
    m_force.setZero();
    return;
  }
  const double n = force.norm();
  m_force = n > m_spec.max_force ? Eigen::Vector2d(force * (m_spec.max_force / n)) : force;
}

void SimulatedProCAT::advance(double dt) {
  // Semi-implicit Euler in 8 substeps: m a = k_g (hand - x) + F - b v - f_c v / max(|v|, 1 mm/s).
  const int sub = 8;
  const double h = dt / sub;
  for (int k = 0; k < sub; ++k) {
    const Eigen::Vector2d hand = m_hand.at(m_t - m_hand_start + (k + 1) * h);
    const double speed = m_v.norm();
    const Eigen::Vector2d friction = m_phys.coulomb * m_v / std::max(speed, 1e-3);
    const Eigen::Vector2d f = m_hand.grip_stiffness * (hand - m_x) + m_force - m_phys.viscous * m_v - friction;
    // Implicit in the viscous and grip terms for unconditional stability at the servo rate.
    const double denom = m_phys.mass + h * m_phys.viscous + h * h * m_hand.grip_stiffness;
    m_v += h * f / denom;
    m_x += h * m_v;
    // The linkage's mechanical stops: the handle stays in the workspace, and a stop takes the
    // velocity into it (an inelastic end stop).
    for (int a = 0; a < 2; ++a) {
      if (m_x[a] < m_spec.workspace_min[a] || m_x[a] > m_spec.workspace_max[a]) {
        m_x[a] = std::clamp(m_x[a], m_spec.workspace_min[a], m_spec.workspace_max[a]);
        m_v[a] = 0;
      }
    }
  }
  m_t += dt;
  // Encoder: positions quantised to counts; velocity by adaptive windowing (velocity_window.hh).
  m_measured = (m_x / m_phys.encoder).array().round().matrix() * m_phys.encoder;
  m_velocity.add(m_t, m_measured);
}

void SimulatedProCAT::move_hand_to(const Eigen::Vector2d& p, double over) {
  const Eigen::Vector2d now = m_hand.at(m_t - m_hand_start);
  m_hand.waypoints.resize(2);
  m_hand.waypoints[0] = now;
  m_hand.waypoints[1] = p;
  m_hand.duration = std::max(over, 1e-9);
  m_hand_start = m_t;
}

ReplayDevice::ReplayDevice(const DeviceSpec& spec, const std::filesystem::path& csv, int probe) : m_spec(spec) {
  std::ifstream f(csv);
  if (!f) throw InputError(csv.string() + ": cannot open the recorded trajectory");
  // Columns by name: t, then hx,hy for probe 0 or hx_<k>,hy_<k> for probe k (haptics.csv's layout).
  const std::string suffix = probe == 0 ? "" : "_" + std::to_string(probe);
  std::string line;
  std::getline(f, line);
  std::vector<std::string> header;
  {
    std::istringstream is(line);
    for (std::string name; std::getline(is, name, ',');) {
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      header.push_back(name);
    }
  }
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw InputError(csv.string() + ":1: no column \"" + name + "\" in the header");
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t ct = column("t"), cx = column("hx" + suffix), cy = column("hy" + suffix);
  int row = 1;
  std::vector<double> values;
  while (std::getline(f, line)) {
    ++row;
    values.clear();
    std::istringstream is(line);
    for (std::string cell; std::getline(is, cell, ',');) {
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      const bool whole =
          end != cell.c_str() &&
          cell.find_first_not_of(" \r", static_cast<std::size_t>(end - cell.c_str())) == std::string::npos;
      values.push_back(whole ? v : std::nan(""));
    }
    const auto at = [&](std::size_t c) { return c < values.size() ? values[c] : std::nan(""); };
    const double t = at(ct), x = at(cx), y = at(cy);
    if (!std::isfinite(t) || !std::isfinite(x) || !std::isfinite(y))
      throw InputError(csv.string() + ":" + std::to_string(row) + ": expected t,hx" + suffix + ",hy" + suffix +
                       " as finite numbers");
    if (!m_time.empty() && t <= m_time.back())
      throw InputError(csv.string() + ":" + std::to_string(row) + ": times must increase");
    m_time.push_back(t);
    m_pos.emplace_back(x, y);
  }
  if (m_time.size() < 2) throw InputError(csv.string() + ": needs at least two samples");
  m_velocity.add(m_t, position_at(m_t));
}

Eigen::Vector2d ReplayDevice::position_at(double t) const {
  const auto it = std::upper_bound(m_time.begin(), m_time.end(), t);
  const std::size_t k = it == m_time.begin() ? 0
                                             : std::min<std::size_t>(static_cast<std::size_t>(it - m_time.begin()) - 1,
                                                                     m_time.size() - 2);
  const double f = std::clamp((t - m_time[k]) / (m_time[k + 1] - m_time[k]), 0.0, 1.0);
  return (1 - f) * m_pos[k] + f * m_pos[k + 1];
}

void ReplayDevice::read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const {
  position = position_at(m_t);
  velocity = m_velocity.velocity();
}

void ReplayDevice::advance(double dt) {
  m_t += dt;
  m_velocity.add(m_t, position_at(m_t));
}

} // namespace vtb
