// hosts/methods/phases.h — what every render method reports: phase timings into the JSON report
// tree, and a progress bar on stderr when it is a terminal.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace zephyr {

// Adds the seconds since construction to report["phases"][name] when Stop() is called (or
// on destruction). Phases with the same name accumulate.
class PhaseTimer {
 public:
  PhaseTimer(nlohmann::json& report, std::string name);
  ~PhaseTimer() { Stop(); }
  double Stop();  // returns the seconds added (0 if already stopped)

 private:
  nlohmann::json& report_;
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
