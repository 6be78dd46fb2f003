#pragma once
/// \file
/// A plain binary encoding of AnyMesh, for passing a mesh between processes.

#include "vtb/meshes/mesh.hh"

#include <string>

namespace vtb {

std::string serialize(const AnyMesh& mesh);
/// Throws InputError("SRC: ...") if the bytes are not a complete encoding.
AnyMesh deserialize(std::string_view bytes, const std::string& src);

} // namespace vtb
