#include "hosts/methods/phases.h"

#include <unistd.h>

#include <cstdio>

namespace zephyr {

PhaseTimer::PhaseTimer(Phases& phases, std::string name)
    : phases_(phases), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}

double PhaseTimer::Stop() {
  if (!running_) return 0;
  running_ = false;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  phases_[name_] += s;
  return s;
}

bool StderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(std::string label, uint64_t total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled && total > 0) {}

void Progress::Advance(uint64_t done) {
  done_ += done;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - lastDraw_ < std::chrono::milliseconds(100) && done_ < total_) return;
  lastDraw_ = now;
  Draw();
}

void Progress::Draw() {
  constexpr int kWidth = 40;
  const double f = total_ ? double(done_) / double(total_) : 1.0;
  const int filled = int(f * kWidth);
  std::string bar(filled, '#');
  bar.append(kWidth - filled, '.');
  std::fprintf(stderr, "\r%s [%s] %3d%%", label_.c_str(), bar.c_str(), int(f * 100));
  std::fflush(stderr);
}

void Progress::Finish() {
  if (!enabled_) return;
  done_ = total_;
  Draw();
  std::fprintf(stderr, "\n");
  enabled_ = false;
}

}  // namespace zephyr
