#include "bitserial/memory.h"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>

#include "fixed/check.h"

namespace zephyr::bitserial {

const char* SpaceName(Space s) { return s == Space::kInternal ? "internal" : "external"; }

PeMemory::PeMemory(int64_t internalBitsPerPe, int64_t externalBitsPerPe, int layers)
    : layers_(layers) {
  ZEPHYR_CHECK_GE(layers, 1);
  capacity_[0] = internalBitsPerPe / layers;
  capacity_[1] = externalBitsPerPe / layers;
  for (int i = 0; i < 2; ++i)
    if (capacity_[i] > 0) gaps_[i][0] = capacity_[i];
}

int64_t PeMemory::Capacity(Space s) const { return capacity_[static_cast<int>(s)]; }
int64_t PeMemory::Used(Space s) const { return used_[static_cast<int>(s)]; }
int64_t PeMemory::PeakUsed(Space s) const { return peak_[static_cast<int>(s)]; }
void PeMemory::ResetPeak() {
  peak_[0] = used_[0];
  peak_[1] = used_[1];
}

std::optional<int64_t> PeMemory::FirstFit(Space s, int64_t bits) const {
  // The lowest-addressed gap that holds `bits`: the same address as walking the variables.
  for (const auto& [address, length] : gaps_[static_cast<int>(s)])
    if (length >= bits) return address;
  return std::nullopt;
}

std::vector<Allocation> PeMemory::Live() const {
  std::vector<Allocation> all;
  for (const auto& space : live_)
    for (const auto& [address, a] : space) all.push_back(a);
  return all;
}

Allocation PeMemory::Allocate(const std::string& name, int64_t bits, std::optional<Space> space) {
  ZEPHYR_CHECK_GE(bits, 1);
  std::optional<int64_t> at;
  Space s = space.value_or(Space::kInternal);
  at = FirstFit(s, bits);
  if (!at && !space) {
    s = Space::kExternal;
    at = FirstFit(s, bits);
  }
  if (!at) {
    auto left = [&](Space x) {
      return fmt::format("{} memory has {} of {} bits free", SpaceName(x), Capacity(x) - Used(x),
                         Capacity(x));
    };
    std::string where =
        space ? left(*space) : left(Space::kInternal) + ", " + left(Space::kExternal);
    throw UserError(fmt::format(
        "PE memory full: multi '{}' needs {} bits per virtual PE; {} (per virtual PE, with {} "
        "virtual-PE layer{} sharing each physical PE's memory)",
        name, bits, where, layers_, layers_ == 1 ? "" : "s"));
  }
  Allocation a{nextId_++, name, s, *at, bits};
  const int i = static_cast<int>(s);
  live_[i].emplace(a.address, a);
  byId_.emplace(a.id, std::pair{s, a.address});
  // The gap it came from: what is left of it starts after the variable.
  auto gap = gaps_[i].find(a.address);
  ZEPHYR_CHECK(gap != gaps_[i].end() && gap->second >= bits);
  const int64_t rest = gap->second - bits;
  gaps_[i].erase(gap);
  if (rest > 0) gaps_[i].emplace(a.address + bits, rest);
  used_[i] += bits;
  peak_[i] = std::max(peak_[i], used_[i]);
  return a;
}

void PeMemory::Free(int id) {
  const auto where = byId_.find(id);
  ZEPHYR_CHECK(where != byId_.end());
  const int i = static_cast<int>(where->second.first);
  const auto it = live_[i].find(where->second.second);
  ZEPHYR_CHECK(it != live_[i].end());
  int64_t start = it->first, length = it->second.bits;
  used_[i] -= length;
  live_[i].erase(it);
  byId_.erase(where);
  // The freed bits become a gap, merged with the gaps just before and after it.
  auto next = gaps_[i].lower_bound(start);
  if (next != gaps_[i].end() && next->first == start + length) {
    length += next->second;
    next = gaps_[i].erase(next);
  }
  if (next != gaps_[i].begin()) {
    auto before = std::prev(next);
    if (before->first + before->second == start) {
      start = before->first;
      length += before->second;
      gaps_[i].erase(before);
    }
  }
  gaps_[i].emplace(start, length);
}

std::string PeMemory::Map() const {
  std::string s =
      fmt::format("PE memory map ({} virtual-PE layer{}; addresses in bits per virtual PE)\n",
                  layers_, layers_ == 1 ? "" : "s");
  for (Space sp : {Space::kInternal, Space::kExternal}) {
    s += fmt::format("  {}: {} of {} bits used (peak {})\n", SpaceName(sp), Used(sp), Capacity(sp),
                     PeakUsed(sp));
    for (const auto& [address, a] : live_[static_cast<int>(sp)])
      s += fmt::format("    {:>7}..{:<7} {:>5} bits  {}\n", a.address, a.address + a.bits - 1,
                       a.bits, a.name);
  }
  return s;
}

}  // namespace zephyr::bitserial
