#include "vtb/haptics/devices/builtin_devices.hh"

#include "vtb/base/input_error.hh"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <exception>
#include <memory>

namespace vtb {
namespace {

using json = nlohmann::json;

Eigen::Vector2d vec2(const json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>()};
}
json to_json(const Eigen::Vector2d& v) {
  return json::array({v.x(), v.y()});
}

json spec_json(const DeviceSpec& s) {
  return {{"max_force", s.max_force},
          {"max_stiffness", s.max_stiffness},
          {"rate_hz", s.rate_hz},
          {"workspace_min", to_json(s.workspace_min)},
          {"workspace_max", to_json(s.workspace_max)}};
}

DeviceSpec spec_of(const json& j) {
  DeviceSpec s;
  s.max_force = j.at("max_force").get<double>();
  s.max_stiffness = j.at("max_stiffness").get<double>();
  s.rate_hz = j.at("rate_hz").get<double>();
  s.workspace_min = vec2(j.at("workspace_min"));
  s.workspace_max = vec2(j.at("workspace_max"));
  return s;
}

void fill_info(const char* name, const DeviceSpec& s, vtb_device_info* info) {
  std::snprintf(info->name, sizeof info->name, "%s", name);
  info->max_force = s.max_force;
  info->max_stiffness = s.max_stiffness;
  for (int a = 0; a < 2; ++a) {
    info->workspace_min[a] = s.workspace_min[a];
    info->workspace_max[a] = s.workspace_max[a];
  }
}

/// open() for a device made by `make(config)`; an exception becomes the one-line reason.
template <class Make> void* open_with(const char* config, char* error, std::size_t size, Make make) {
  try {
    return make(json::parse(config)).release();
  } catch (const std::exception& e) {
    std::snprintf(error, size, "%s", e.what());
    return nullptr;
  }
}

int read_device(void* d, vtb_device_state* s) {
  Eigen::Vector2d p, v;
  static_cast<HapticDevice*>(d)->read(p, v);
  s->position[0] = p.x();
  s->position[1] = p.y();
  s->velocity[0] = v.x();
  s->velocity[1] = v.y();
  return 0;
}
int write_device(void* d, const vtb_device_command* c) {
  static_cast<HapticDevice*>(d)->command(Eigen::Vector2d(c->force[0], c->force[1]));
  return 0;
}
void advance_device(void* d, double dt) {
  static_cast<HapticDevice*>(d)->advance(dt);
}
void close_device(void* d) {
  delete static_cast<HapticDevice*>(d);
}

/// The null device: a handle held at `rest`, rendering nothing.
class NullDevice final : public HapticDevice {
public:
  NullDevice(const DeviceSpec& spec, const Eigen::Vector2d& rest) : m_spec(spec), m_rest(rest) {}
  const DeviceSpec& spec() const override { return m_spec; }
  void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const override {
    position = m_rest;
    velocity.setZero();
  }
  void command(const Eigen::Vector2d&) override {}
  void advance(double) override {}

private:
  DeviceSpec m_spec;
  Eigen::Vector2d m_rest;
};

void* open_null(const char* config, vtb_device_info* info, char* error, std::size_t size) {
  return open_with(config, error, size, [&](const json& j) {
    DeviceSpec s;
    s.max_force = info->max_force;
    fill_info("null", s, info);
    return std::make_unique<NullDevice>(s, vec2(j.at("rest")));
  });
}

void* open_procat(const char* config, vtb_device_info* info, char* error, std::size_t size) {
  return open_with(config, error, size, [&](const json& j) {
    const DeviceSpec s = spec_of(j.at("spec"));
    HandScript hand;
    for (const auto& w : j.at("waypoints")) hand.waypoints.push_back(vec2(w));
    hand.duration = j.at("duration").get<double>();
    hand.grip_stiffness = j.at("grip_stiffness").get<double>();
    fill_info("procat-sim", s, info);
    return std::make_unique<SimulatedProCAT>(s, std::move(hand));
  });
}

void* open_replay(const char* config, vtb_device_info* info, char* error, std::size_t size) {
  return open_with(config, error, size, [&](const json& j) {
    const DeviceSpec s = spec_of(j.at("spec"));
    fill_info("replay", s, info);
    return std::make_unique<ReplayDevice>(s, j.at("file").get<std::string>(), j.at("probe").get<int>());
  });
}

constexpr vtb_device_api kNull{VTB_DEVICE_ABI_VERSION, open_null,      read_device,
                               write_device,           advance_device, close_device};
constexpr vtb_device_api kProcat{VTB_DEVICE_ABI_VERSION, open_procat,    read_device,
                                 write_device,           advance_device, close_device};
constexpr vtb_device_api kReplay{VTB_DEVICE_ABI_VERSION, open_replay,    read_device,
                                 write_device,           advance_device, close_device};

} // namespace

const vtb_device_api* builtin_device_api(const std::string& name) {
  if (name == "null") return &kNull;
  if (name == "procat-sim") return &kProcat;
  if (name == "replay") return &kReplay;
  return nullptr;
}

std::string procat_sim_config(const DeviceSpec& spec, const HandScript& hand) {
  json w = json::array();
  for (const auto& p : hand.waypoints) w.push_back(to_json(p));
  // 17 digits: the script reaches the device bit for bit.
  return json{
      {"spec", spec_json(spec)}, {"waypoints", w}, {"duration", hand.duration}, {"grip_stiffness", hand.grip_stiffness}}
      .dump();
}

std::string replay_config(const DeviceSpec& spec, const std::filesystem::path& csv, int probe) {
  return json{{"spec", spec_json(spec)}, {"file", csv.string()}, {"probe", probe}}.dump();
}

std::string null_config(const Eigen::Vector2d& rest) {
  return json{{"rest", to_json(rest)}}.dump();
}

} // namespace vtb
