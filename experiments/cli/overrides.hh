#pragma once
/// \file
/// The CLI's own parsing that turns options into what the libraries take: `vtb haptics
/// --fault` (`vtb run`'s overrides are the harness's, vtb/harness/solvers.hh).

#include "vtb/haptics/session.hh"
#include "vtb/harness/solvers.hh"
#include "vtb/problem/scene.hh"

#include <optional>
#include <string>

namespace vtb::cli {

using harness::RunOverrides;
using harness::with_overrides;

/// Parses "stall@T" or "nan@T" (T >= 0 in seconds) into the fault and its time; InputError
/// naming --fault otherwise.
HapticsOptions::Fault parse_fault(const std::string& spec, double& time);

} // namespace vtb::cli
