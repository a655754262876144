// hosts/farm/common.h — small helpers the farm's parent and child share (not for other rooms):
// the clock, and text ↔ payload bytes.
#pragma once

#include <chrono>
#include <cstddef>
#include <span>
#include <string>

#include "hosts/farm/session.h"

namespace zephyr::farm {

using Clock = std::chrono::steady_clock;
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
