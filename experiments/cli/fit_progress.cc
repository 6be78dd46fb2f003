#include "fit_progress.hh"

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

namespace vtb::cli {

FitProgress fit_progress_line(std::ostream& os, bool terminal) {
  struct Line {
    std::chrono::steady_clock::time_point start; ///< the fit's first call
    bool started = false;
    std::string last_stage;
    bool drawn = false;
  };
  auto line = std::make_shared<Line>();
  return [&os, terminal, line](const char* stage, int step, int steps) {
    if (!line->started) line->start = std::chrono::steady_clock::now(), line->started = true;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - line->start).count();
    const std::string what = stage;
    if (what == "done") {
      if (line->drawn) os << (terminal ? "\n" : "") << "vtb: springs fitted in " << seconds << " s\n" << std::flush;
      return;
    }
    if (seconds < 2.0) return;
    // Logs get the fit's steps and the first modes line only; a terminal gets every call.
    if (!terminal && what == "modes" && what == line->last_stage) return;
    line->last_stage = what;
    char text[120];
    std::snprintf(text, sizeof text, "vtb: fitting springs: %s %d (at most %d), %.0f s",
                  what == "modes" ? "training modes, iteration" : "Levenberg-Marquardt step", step, steps, seconds);
    os << (terminal ? "\r" : "") << text << (terminal ? "   " : "\n") << std::flush;
    line->drawn = true;
  };
}

} // namespace vtb::cli
