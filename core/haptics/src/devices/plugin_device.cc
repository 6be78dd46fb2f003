#include "vtb/haptics/devices/plugin_device.hh"

#include "vtb/base/input_error.hh"
#include "vtb/haptics/force_shaping.hh"

#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace vtb {

std::unique_ptr<PluginDevice> PluginDevice::load(const std::filesystem::path& library, const std::string& config,
                                                 const DeviceSpec& host) {
  const std::string where = library.string();
  if (!std::filesystem::exists(library)) throw InputError(where + ": no such device plug-in");
  // RTLD_LOCAL: a plug-in's symbols stay its own; RTLD_NOW: a missing symbol fails here, not in the servo.
  void* handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* why = dlerror();
    throw InputError(where + ": cannot load the device plug-in: " + (why ? why : "unknown error"));
  }
  auto entry = reinterpret_cast<vtb_device_entry_fn>(dlsym(handle, VTB_DEVICE_ENTRY_SYMBOL));
  if (!entry) {
    dlclose(handle);
    throw InputError(where + ": not a vtb device plug-in (it exports no " VTB_DEVICE_ENTRY_SYMBOL ")");
  }
  const vtb_device_api* api = entry(VTB_DEVICE_ABI_VERSION);
  if (!api || api->abi_version != VTB_DEVICE_ABI_VERSION) {
    const std::string theirs = api ? std::to_string(api->abi_version) : std::string("none (it refused this host)");
    dlclose(handle);
    throw InputError(where + ": device plug-in ABI version " + theirs + "; this vtb speaks version " +
                     std::to_string(VTB_DEVICE_ABI_VERSION) + " (rebuild it against this vtb's device_abi.h)");
  }
  try {
    return std::make_unique<PluginDevice>(api, where, config, host, handle);
  } catch (...) {
    dlclose(handle);
    throw;
  }
}

PluginDevice::PluginDevice(const vtb_device_api* api, const std::string& source, const std::string& config,
                           const DeviceSpec& host, void* library)
    : m_api(api), m_spec(host) {
  if (!api->open || !api->read || !api->write || !api->close)
    throw InputError(source + ": the device plug-in's table lacks open, read, write or close");
  vtb_device_info info{};
  std::snprintf(info.name, sizeof info.name, "%s", std::filesystem::path(source).stem().c_str());
  info.max_force = host.max_force;
  info.max_stiffness = host.max_stiffness;
  for (int a = 0; a < 2; ++a) {
    info.workspace_min[a] = host.workspace_min[a];
    info.workspace_max[a] = host.workspace_max[a];
  }
  std::array<char, 256> error{};
  m_device = api->open(config.c_str(), &info, error.data(), error.size());
  if (!m_device) {
    error.back() = '\0';
    throw InputError(source + ": the device did not open: " + (error[0] ? error.data() : "no reason given"));
  }
  m_library = library;
  info.name[sizeof info.name - 1] = '\0';
  m_name = info.name;
  // The device's limits, never above the scene's: a plug-in can lower them, not raise them.
  if (std::isfinite(info.max_force) && info.max_force > 0) m_spec.max_force = std::min(host.max_force, info.max_force);
  if (std::isfinite(info.max_stiffness) && info.max_stiffness > 0)
    m_spec.max_stiffness = std::min(host.max_stiffness, info.max_stiffness);
  const Eigen::Vector2d lo(info.workspace_min[0], info.workspace_min[1]),
      hi(info.workspace_max[0], info.workspace_max[1]);
  if (lo.allFinite() && hi.allFinite() && (hi.array() > lo.array()).all()) {
    m_spec.workspace_min = lo;
    m_spec.workspace_max = hi;
  }
}

PluginDevice::~PluginDevice() {
  if (m_device) {
    send_zero();
    m_api->close(m_device);
  }
  if (m_library) dlclose(m_library);
}

void PluginDevice::read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const {
  vtb_device_state s{};
  const int status = m_fault ? 0 : m_api->read(m_device, &s);
  const Eigen::Vector2d p(s.position[0], s.position[1]), v(s.velocity[0], s.velocity[1]);
  if (!m_fault && (status != 0 || !p.allFinite() || !v.allFinite())) {
    m_fault = true; // latched: a device that returned garbage once is not trusted again this session
    ++m_stats.faults;
  }
  if (!m_fault) m_last_position = p;
  position = m_last_position;
  velocity = m_fault ? Eigen::Vector2d::Zero() : v;
}

void PluginDevice::command(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor, double t) {
  m_t = t;
  vtb_device_command c{};
  m_zeroed = m_fault;
  const Eigen::Vector2d f = m_fault ? Eigen::Vector2d::Zero() : saturate(force, m_spec.max_force);
  c.force[0] = f.x();
  c.force[1] = f.y();
  c.stiffness = !m_fault && std::isfinite(stiffness) ? std::clamp(stiffness, 0.0, m_spec.max_stiffness) : 0.0;
  c.anchor[0] = anchor.allFinite() ? anchor.x() : m_last_position.x();
  c.anchor[1] = anchor.allFinite() ? anchor.y() : m_last_position.y();
  c.time = t;
  if (m_api->write(m_device, &c) != 0 && !m_fault) {
    m_fault = true;
    ++m_stats.faults;
  }
}

void PluginDevice::advance(double dt) {
  m_t += dt;
  if (m_api->advance) m_api->advance(m_device, dt);
}

void PluginDevice::send_zero() {
  vtb_device_command c{};
  c.anchor[0] = m_last_position.x();
  c.anchor[1] = m_last_position.y();
  c.time = m_t;
  m_api->write(m_device, &c);
}

} // namespace vtb
