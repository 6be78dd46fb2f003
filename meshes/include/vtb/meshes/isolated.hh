#pragma once
/// \file
/// Reading untrusted input: the file read whole under a size cap, and the reader run in a forked
/// child process (a reader that crashes, hangs or prints is contained, and its caller gets one
/// line). The .msh reader (gmsh) and the surface readers (CGAL) run through both.

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>

namespace vtb {

/// The file's bytes. Throws InputError "FILE: cannot open WHAT file" when it cannot be read, and
/// "FILE: WHAT file larger than 1 GiB; refused" beyond that size (`what`: "mesh", "surface").
std::string read_untrusted(const std::filesystem::path& file, const std::string& what);

/// Forks; the child runs `work` (its stdout and stderr go to /dev/null) and sends back what it
/// returns, or the message of an exception it throws. Returns the child's bytes. Throws
/// InputError "SRC: ..." when the child crashed (the signal), ran past `limit`, failed, or threw
/// (its message, which names SRC itself). `what` names the reader in those lines ("mesh",
/// "surface"). Must not be called while other threads run (it forks).
std::string run_isolated(const std::string& src, const std::string& what, std::chrono::seconds limit,
                         const std::function<std::string()>& work);

} // namespace vtb
