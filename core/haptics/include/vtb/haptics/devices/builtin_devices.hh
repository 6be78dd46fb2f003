#pragma once
/// \file
/// vtb's own devices on the plug-in ABI (device_abi.h), compiled in: `null` (a handle held still
/// out of reach, rendering nothing), `procat-sim` (the simulated ProCAT pushed by a scripted hand,
/// device.hh) and `replay` (a recorded trajectory). Each is opened from a JSON config that
/// builtin_config writes, so a session drives them exactly as it drives a loaded plug-in.

#include "vtb/haptics/device.hh"
#include "vtb/haptics/devices/device_abi.h"

#include <filesystem>
#include <string>

namespace vtb {

/// The table of the built-in device `name` ("null", "procat-sim", "replay"), or null.
const vtb_device_api* builtin_device_api(const std::string& name);

/// The configs the built-in devices read: the hand's script and the device's limits; the
/// recorded file and its probe; the null handle's resting point.
std::string procat_sim_config(const DeviceSpec& spec, const HandScript& hand);
std::string replay_config(const DeviceSpec& spec, const std::filesystem::path& csv, int probe);
std::string null_config(const Eigen::Vector2d& rest);

} // namespace vtb
