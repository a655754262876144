#include "hosts/methods/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "fixed/check.h"
#include "fmt/format.h"

namespace zephyr {

namespace {

// The process's mapped address space and data, bytes (/proc/self/statm: size and data, in pages).
void MappedNow(uint64_t& address, uint64_t& data) {
  address = data = 0;
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0, shared = 0, text = 0, lib = 0, dataPages = 0;
  if (statm >> size >> resident >> shared >> text >> lib >> dataPages) {
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    address = size * page;
    data = dataPages * page;
  }
}

double GiB(uint64_t bytes) { return double(bytes) / double(uint64_t(1) << 30); }

}  // namespace

MemoryLimit AvailableMemory() {
  MemoryLimit best;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  best.bytes = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : UINT64_MAX;
  best.source = "the machine's physical memory";
  uint64_t address = 0, data = 0;
  MappedNow(address, data);
  auto consider = [&](int resource, uint64_t used, const char* name) {
    struct rlimit r;
    if (::getrlimit(resource, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return;
    const uint64_t left = r.rlim_cur > used ? uint64_t(r.rlim_cur) - used : 0;
    if (left < best.bytes)
      best = {left, fmt::format("{} of {:.2f} GiB less the {:.2f} GiB mapped now", name,
                                GiB(r.rlim_cur), GiB(used))};
  };
  consider(RLIMIT_AS, address, "RLIMIT_AS (ulimit -v)");
  consider(RLIMIT_DATA, data, "RLIMIT_DATA (ulimit -d)");
  return best;
}

void CheckMemoryFits(const std::string& what, const MemoryNeed& need) {
  CheckMemoryFits(what, need, AvailableMemory());
}

void CheckMemoryFits(const std::string& what, const MemoryNeed& need, const MemoryLimit& limit) {
  if (need.Bytes() <= limit.bytes) return;
  const double room = limit.bytes > need.fixedBytes ? double(limit.bytes - need.fixedBytes) : 0.0;
  const int side = need.perPixel > 0 ? int(std::floor(std::sqrt(room / need.perPixel))) : 0;
  throw UserError(fmt::format(
      "{} needs about {:.2f} GiB ({} pixels at {:g} bytes each, docs/errors.md \"Memory\"), more "
      "than the "
      "{:.2f} GiB this process may have ({}); {}",
      what, GiB(need.Bytes()), need.pixels, need.perPixel, GiB(limit.bytes), limit.source,
      side > 0 ? fmt::format("the largest square image that fits is about {}x{}", side, side)
               : std::string("no image fits")));
}

}  // namespace zephyr
