#pragma once
/// \file
/// A device behind the C ABI of device_abi.h: a plug-in loaded from a shared library at run
/// time, or one of vtb's own devices (builtin_devices.hh) on the same table, so the servo drives
/// every device through one path. The host side owns the safety: every command is clamped to
/// the device's limit (direction kept; a non-finite force is 0 N), a failed or non-finite read
/// latches a fault after which 0 N is sent, and 0 N is sent before close.

#include "vtb/haptics/device.hh"
#include "vtb/haptics/devices/device_abi.h"

#include <filesystem>
#include <memory>
#include <string>

namespace vtb {

class PluginDevice final : public HapticDevice {
public:
  /// Loads `library` (dlopen), asks its `vtb_device_entry` for the table of this ABI version and
  /// opens the device with `config`. Throws InputError, one line naming the library: not found,
  /// no entry, another ABI version, or the plug-in's own reason for refusing to open.
  static std::unique_ptr<PluginDevice> load(const std::filesystem::path& library, const std::string& config,
                                            const DeviceSpec& host);
  /// A table compiled into vtb (`source` names it in messages); `library` is a dlopen handle
  /// this device closes at the end, or null.
  PluginDevice(const vtb_device_api* api, const std::string& source, const std::string& config, const DeviceSpec& host,
               void* library = nullptr);
  ~PluginDevice() override;
  PluginDevice(const PluginDevice&) = delete;
  PluginDevice& operator=(const PluginDevice&) = delete;

  const DeviceSpec& spec() const override { return m_spec; }
  void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const override;
  void command(const Eigen::Vector2d& force) override { command(force, 0.0, m_last_position, m_t); }
  void command(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor, double t) override;
  void advance(double dt) override;
  std::string name() const override { return m_name; }
  DeviceLinkStats link_stats() const override { return m_stats; }
  bool zeroed() const override { return m_zeroed; }
  /// The ABI's table, to check what a plug-in declared (tests).
  const vtb_device_api& api() const { return *m_api; }

private:
  void send_zero();
  const vtb_device_api* m_api;
  void* m_device = nullptr;
  void* m_library = nullptr;
  DeviceSpec m_spec;
  std::string m_name;
  double m_t = 0;
  mutable DeviceLinkStats m_stats;
  mutable bool m_fault = false;
  bool m_zeroed = false; ///< the last command was sent as 0 N (the fault)
  mutable Eigen::Vector2d m_last_position = Eigen::Vector2d::Zero();
};

} // namespace vtb
