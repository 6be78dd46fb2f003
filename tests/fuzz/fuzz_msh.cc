// libFuzzer target for vtb's own .msh hardening, in process: the pre-scan of declared counts
// (text input), and the decoding plus checking of a mesh handed over by the isolated reader
// (input starting with 'M'). gmsh itself runs in a child process whose crashes become
// refusals (tests/meshes/test_msh_io.cc holds a file that crashes it); it is not
// instrumented, so it is not fuzzed here.
#include "vtb/base/input_error.hh"
#include "vtb/meshes/mesh_serialize.hh"
#include "vtb/meshes/msh_prescan.hh"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  try {
    if (!in.empty() && in[0] == 'M') {
      vtb::AnyMesh m = vtb::deserialize(in.substr(1), "fuzz");
      std::visit([](auto& mesh) { vtb::check_and_orient(mesh); }, m);
    } else {
      vtb::prescan_msh(in, "fuzz.msh");
    }
  } catch (const vtb::InputError&) {
  }
  return 0;
}
