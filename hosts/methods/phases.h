// hosts/methods/phases.h — what every render method reports: phase timings (typed, written into
// the report by hosts/methods/report.h), and a progress bar on stderr when it is a terminal.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>

namespace zephyr {

// Wall seconds per phase of a render, by name (lowerCamel: "readScene", "render",
// "primaryPass", "hostShading", "writePng", "dumpPrimary"; docs/background.md).
using Phases = std::map<std::string, double>;

// Adds the seconds since construction to phases[name] when Stop() is called (or on
// destruction). Phases with the same name accumulate.
class PhaseTimer {
 public:
  PhaseTimer(Phases& phases, std::string name);
  ~PhaseTimer() { Stop(); }
  double Stop();  // returns the seconds added (0 if already stopped)

 private:
  Phases& phases_;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
  bool running_ = true;
};

// "render [#####.....]  52%" on stderr, redrawn at most ~10 times a second; silent unless
// stderr is a terminal (or when forced off).
class Progress {
 public:
  Progress(std::string label, uint64_t total, bool enabled);
  ~Progress() { Finish(); }
  void Advance(uint64_t done = 1);
  void Finish();

 private:
  void Draw();
  std::string label_;
  uint64_t total_, done_ = 0;
  bool enabled_;
  std::chrono::steady_clock::time_point lastDraw_{};
};

bool StderrIsTerminal();

}  // namespace zephyr
