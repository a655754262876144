// tests/bitserial/testing.h — helpers shared by the bitserial tests: the four policies,
// every compiled Highway target, small formats and all their value pairs, and the cycles
// of one operation on fresh random operands.
#pragma once

#include <gtest/gtest.h>
#include <hwy/targets.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/format.h"

namespace zephyr::bitserial::testutil {

inline const fixed::Policy kPolicies[] = {
    {fixed::Rounding::kFloor, fixed::OverflowPolicy::kWrap},
    {fixed::Rounding::kNearest, fixed::OverflowPolicy::kWrap},
    {fixed::Rounding::kFloor, fixed::OverflowPolicy::kSaturate},
    {fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate}};

// Runs `body` once per compiled Highway target (hwy's own test pattern).
inline void ForEachTarget(const std::function<void()>& body) {
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    body();
  }
  hwy::SetSupportedTargetsForTest(0);
}

// Formats of width <= 6, signed and unsigned, with different splits.
inline std::vector<fixed::Format> SmallFormats() {
  using fixed::Format;
  return {Format::Signed(2, 3),   Format::Unsigned(3, 3), Format::Signed(0, 2),
          Format::Unsigned(1, 0), Format::Signed(4, 0),   Format::Unsigned(0, 5)};
}

// Every pair of values of fa and fb (at most 4096 for widths <= 6), one pair per PE.
inline void AllPairs(const fixed::Format& fa, const fixed::Format& fb, std::vector<fixed::Fixed>& a,
                     std::vector<fixed::Fixed>& b) {
  a.clear(), b.clear();
  for (int i = 0; i < (1 << fa.Width()); ++i)
    for (int j = 0; j < (1 << fb.Width()); ++j) {
      a.push_back(fixed::Fixed::FromBits(fa, i));
      b.push_back(fixed::Fixed::FromBits(fb, j));
    }
}

// Runs `op` on fresh random operands of formats fa, fb and returns the cycles charged to
// `name` (which must be charged exactly once).
template <typename Op>
double Cycles(const std::string& profile, const fixed::Format& fa, const fixed::Format& fb,
              const char* name, Op op, uint64_t seed = 1, int64_t virtualPes = 0) {
  Machine m(Profile(profile), virtualPes);
  std::mt19937_64 rng(seed);
  std::vector<int64_t> ra(m.VirtualPes()), rb(m.VirtualPes());
  for (auto& x : ra) x = static_cast<int64_t>(rng() >> (64 - fa.Width()));
  for (auto& x : rb) x = static_cast<int64_t>(rng() >> (64 - fb.Width()));
  Multi a(m, fa, "a"), b(m, fb, "b");
  a.LoadRaw(ra);
  b.LoadRaw(rb);
  Multi r = op(a, b);
  EXPECT_EQ(m.Report().OpCalls(name), 1);
  return m.Report().OpCycles(name);
}

inline void ExpectFormula(double got, double formula, const std::string& what) {
  EXPECT_EQ(got, formula) << what;
}

// The micro-op counts (name → count over all layers) charged to `op` by one call.
inline std::map<std::string, int64_t> ChargedMicroOps(Machine& m, const std::string& op) {
  const nlohmann::json j = m.Report().Json();
  EXPECT_EQ(m.Report().OpCalls(op), 1) << op;
  std::map<std::string, int64_t> counts;
  if (!j["byOp"].contains(op)) return counts;
  for (auto& [name, k] : j["byOp"][op]["microOps"].items()) counts[name] = k.get<int64_t>();
  return counts;
}

}  // namespace zephyr::bitserial::testutil
