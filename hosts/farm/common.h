// hosts/farm/common.h — small helpers the farm's parent and child share (not for other rooms):
// the clock, and text ↔ payload bytes.
#pragma once

#include <chrono>
#include <cstddef>
#include <span>
#include <string>

#include "hosts/farm/session.h"

#ifdef ZEPHYR_SMPI
#include <simgrid/engine.h>
#endif

namespace zephyr::farm {

#ifdef ZEPHYR_SMPI
// Under SimGrid (zephyr-smpi, docs/testbed.md) the farm's clock is the simulated one: the
// seconds it reports (a child's set-up, busy and idle time in its stats message) and the
// decisions it takes on time then depend on the simulation only, so two runs of the same
// render send the same bytes and end at the same simulated second. Wall-clock time would
// change the stats message's digits, hence its transfer time on the simulated Ethernet.
struct Clock {
  using duration = std::chrono::duration<double>;
  using rep = duration::rep;
  using period = duration::period;
  using time_point = std::chrono::time_point<Clock, duration>;
  static constexpr bool is_steady = true;
  static time_point now() { return time_point(duration(simgrid_get_clock())); }
};
#else
using Clock = std::chrono::steady_clock;
#endif
inline double SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

inline std::span<const std::byte> Bytes(const std::string& s) {
  return std::as_bytes(std::span(s.data(), s.size()));
}
inline std::string Text(std::span<const std::byte> b) {
  return std::string(reinterpret_cast<const char*>(b.data()), b.size());
}

// Starts MPI and checks there is a parent and at least one child; UserError naming `method`
// (as the user launched it) otherwise.
MpiSession& StartFarm(const std::string& method);

}  // namespace zephyr::farm
