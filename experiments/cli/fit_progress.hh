#pragma once
/// \file
/// The terminal's progress line for a spring fit (springs = "fitted" or "auto"): silent for
/// the first two seconds, so that small fits and cache reads print nothing; then one line,
/// redrawn in place on a terminal and written once per stage and fit step otherwise (logs).

#include "vtb/springs/fitted_springs.hh"

#include <ostream>

namespace vtb::cli {

/// A FitProgress that draws on `os` (which must outlive the fit).
FitProgress fit_progress_line(std::ostream& os, bool terminal);

} // namespace vtb::cli
