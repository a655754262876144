#include "bitserial/memory.h"

#include <fmt/format.h>

#include <algorithm>

#include "fixed/check.h"

namespace zephyr::bitserial {

const char* SpaceName(Space s) { return s == Space::kInternal ? "internal" : "external"; }

PeMemory::PeMemory(int64_t internalBitsPerPe, int64_t externalBitsPerPe, int layers)
    : layers_(layers) {
  ZEPHYR_CHECK_GE(layers, 1);
  capacity_[0] = internalBitsPerPe / layers;
  capacity_[1] = externalBitsPerPe / layers;
}

int64_t PeMemory::Capacity(Space s) const { return capacity_[static_cast<int>(s)]; }
int64_t PeMemory::Used(Space s) const { return used_[static_cast<int>(s)]; }
int64_t PeMemory::PeakUsed(Space s) const { return peak_[static_cast<int>(s)]; }
void PeMemory::ResetPeak() {
  peak_[0] = used_[0];
  peak_[1] = used_[1];
}

std::optional<int64_t> PeMemory::FirstFit(Space s, int64_t bits) const {
  int64_t next = 0;
  for (const Allocation& a : live_) {
    if (a.space != s) continue;
    if (a.address - next >= bits) return next;
    next = a.address + a.bits;
  }
  if (Capacity(s) - next >= bits) return next;
  return std::nullopt;
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
  auto pos =
      std::lower_bound(live_.begin(), live_.end(), a, [](const Allocation& x, const Allocation& y) {
        return std::tie(x.space, x.address) < std::tie(y.space, y.address);
      });
  live_.insert(pos, a);
  int i = static_cast<int>(s);
  used_[i] += bits;
  peak_[i] = std::max(peak_[i], used_[i]);
  return a;
}

void PeMemory::Free(int id) {
  auto it =
      std::find_if(live_.begin(), live_.end(), [&](const Allocation& a) { return a.id == id; });
  ZEPHYR_CHECK(it != live_.end());
  used_[static_cast<int>(it->space)] -= it->bits;
  live_.erase(it);
}

std::string PeMemory::Map() const {
  std::string s =
      fmt::format("PE memory map ({} virtual-PE layer{}; addresses in bits per virtual PE)\n",
                  layers_, layers_ == 1 ? "" : "s");
  for (Space sp : {Space::kInternal, Space::kExternal}) {
    s += fmt::format("  {}: {} of {} bits used (peak {})\n", SpaceName(sp), Used(sp), Capacity(sp),
                     PeakUsed(sp));
    for (const Allocation& a : live_)
      if (a.space == sp)
        s += fmt::format("    {:>7}..{:<7} {:>5} bits  {}\n", a.address, a.address + a.bits - 1,
                         a.bits, a.name);
  }
  return s;
}

}  // namespace zephyr::bitserial
