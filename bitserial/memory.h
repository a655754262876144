// bitserial/memory.h — the PE memory address spaces and what lives where.
//
// Every multi variable has a width and an address (in bits) in the internal (2048 bits per
// PE on the WaveTracer) or the external (32 KB per PE) memory. With n virtual-PE layers
// each virtual PE owns 1/n of each physical PE's memory (paper §5.1, docs/background.md: "the
// controller splits each PE's memory into n equal parts"), so addresses here are per virtual PE and
// the capacity is floor(physical capacity / n). Allocation is first fit in address order, so the
// same program always gets the same layout.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace zephyr::bitserial {

// The two address spaces of a PE (internal: 2 Kbit on the WaveTracer; external: 32 KB).
enum class Space : int { kInternal, kExternal };
const char* SpaceName(Space s);

struct Allocation {
  int id = -1;
  std::string name;
  Space space = Space::kInternal;
  int64_t address = 0;  // first bit, per virtual PE
  int64_t bits = 0;
};

class PeMemory {
 public:
  PeMemory(int64_t internalBitsPerPe, int64_t externalBitsPerPe, int layers);

  // Places `bits` bits in `space`, or (no space given) internal if it fits, else external.
  // Throws UserError naming the variable, its size and what is left when it does not fit.
  Allocation Allocate(const std::string& name, int64_t bits,
                      std::optional<Space> space = std::nullopt);
  void Free(int id);

  int64_t Capacity(Space s) const;  // bits per virtual PE
  int64_t Used(Space s) const;
  int64_t PeakUsed(Space s) const;
  // Starts the peaks again from the bits live now, so that PeakUsed() measures one part of a
  // program alone (the planner's per-object temporaries, hosts/simd/program.h).
  void ResetPeak();
  int Layers() const { return layers_; }
  // The live variables, in (space, address) order.
  std::vector<Allocation> Live() const;
  // The printable memory map: one line per live variable, in address order.
  std::string Map() const;

 private:
  std::optional<int64_t> FirstFit(Space s, int64_t bits) const;

  int64_t capacity_[2];
  int64_t used_[2] = {0, 0};
  int64_t peak_[2] = {0, 0};
  int layers_;
  int nextId_ = 0;
  // Per space: the live variables by address, and the free gaps (address -> length, the tail
  // after the last variable included), so that a program holding thousands of variables (one
  // per light of a scene) allocates and frees in O(log n + gaps), not O(n) (issue 39: 2000
  // lights took 103 s, two thirds of it here).
  std::map<int64_t, Allocation> live_[2];
  std::map<int64_t, int64_t> gaps_[2];
  std::unordered_map<int, std::pair<Space, int64_t>> byId_;  // id -> (space, address)
};

}  // namespace zephyr::bitserial
