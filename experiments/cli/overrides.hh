#pragma once
/// \file
/// The CLI's own parsing that turns options into what the libraries take: `vtb run`'s
/// overrides of a scene, and `vtb haptics --fault`.

#include "vtb/haptics/session.hh"
#include "vtb/problem/scene.hh"

#include <optional>
#include <string>

namespace vtb::cli {

/// Options of `vtb run` that override the scene.
struct RunOverrides {
  std::optional<std::string> solver;
  std::optional<double> dt;
  std::optional<double> duration;
};

/// The scene with `vtb run`'s overrides applied; InputError for a non-positive or
/// non-finite --dt/--duration, or a step longer than the run.
Scene with_overrides(const Scene& scene, const RunOverrides& overrides);

/// Parses "stall@T" or "nan@T" (T >= 0 in seconds) into the fault and its time; InputError
/// naming --fault otherwise.
HapticsOptions::Fault parse_fault(const std::string& spec, double& time);

} // namespace vtb::cli
