// hosts/methods/memory_budget.h — a run's memory, estimated before any work and compared
// with what the process may have, so an image larger than memory is a clear refusal (both
// figures and the largest image that fits), never a std::bad_alloc (docs/errors.md,
// "Memory").
//
//   CheckMemoryFits("render --method seq", {.perPixel = 26, .pixels = w * h});
#pragma once

#include <cstdint>
#include <string>

namespace zephyr {

// The memory this process may still allocate: the tightest of RLIMIT_AS less the address
// space mapped now, RLIMIT_DATA less the data mapped now, and the physical memory
// (sysconf). `source` names which ("RLIMIT_AS (ulimit -v)", "physical memory").
struct MemoryLimit {
  uint64_t bytes = 0;
  std::string source;
};
MemoryLimit AvailableMemory();

// A run's peak memory as fixed bytes plus bytes per pixel (the figures of each method are
// measured peaks, docs/errors.md "Memory", with a margin).
struct MemoryNeed {
  double perPixel = 0;             // bytes per image pixel at the peak
  uint64_t pixels = 0;             // the image's pixels
  uint64_t fixedBytes = 64 << 20;  // the program, its libraries' heaps, per-thread arenas
  uint64_t Bytes() const { return fixedBytes + uint64_t(perPixel * double(pixels)); }
};

// UserError when `need` is more than AvailableMemory() (or `limit` when given): "WHAT needs
// about X GiB (N pixels at B bytes each), more than the Y GiB this process may have (SOURCE);
// the largest square image that fits is about S×S".
void CheckMemoryFits(const std::string& what, const MemoryNeed& need);
void CheckMemoryFits(const std::string& what, const MemoryNeed& need, const MemoryLimit& limit);

}  // namespace zephyr
