#pragma once
/// \file
/// Runs a reader of untrusted input in a forked child process: a reader that crashes, hangs or
/// prints is contained, and its caller gets one line. The .msh reader (gmsh) and the surface
/// readers (CGAL) run through it.

#include <chrono>
#include <functional>
#include <string>

namespace vtb {

/// Forks; the child runs `work` (its stdout and stderr go to /dev/null) and sends back what it
/// returns, or the message of an exception it throws. Returns the child's bytes. Throws
/// InputError "SRC: ..." when the child crashed (the signal), ran past `limit`, failed, or threw
/// (its message, which names SRC itself). `what` names the reader in those lines ("mesh",
/// "surface"). Must not be called while other threads run (it forks).
std::string run_isolated(const std::string& src, const std::string& what, std::chrono::seconds limit,
                         const std::function<std::string()>& work);

} // namespace vtb
