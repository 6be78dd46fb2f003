#pragma once
/// \file
/// A cheap structural check of a .msh file before any reader allocates for it: a mesh file
/// is untrusted input, and a header that declares 10^15 nodes must be refused, not obeyed.

#include <string>
#include <string_view>

namespace vtb {

/// Checks the $MeshFormat version (2.2, 4.0, 4.1; ASCII or binary) and that every declared
/// count ($Nodes, $Elements, entity blocks, tag ranges) fits in the file's size. Throws
/// InputError "SRC: ..." naming the section and the count otherwise.
void prescan_msh(std::string_view content, const std::string& src);

} // namespace vtb
