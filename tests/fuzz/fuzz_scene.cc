// libFuzzer target: the scene parser must refuse anything with InputError, never crash.
#include "vtb/problem/scene.hh"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    vtb::parse_scene(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.toml", ".");
  } catch (const vtb::InputError&) {
  }
  return 0;
}
