// Hardware-fidelity tests 2 and 3: cycle counts equal each op's closed form (docs/
// bitserial.md) at N and not N-1, do not depend on the data, scale with the layers, and the
// MPP profile reproduces Batcher's published figures from the same engine code.
#include <gtest/gtest.h>

#include <random>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;
using testutil::Cycles;
using testutil::ExpectFormula;

TEST(BitserialCycles, MppReproducesBatcher1980) {
  // 8-bit add = 25 cycles (6553 MOPS on 16384 PEs at 100 ns), 8x8 multiply = 88 (1861 MOPS).
  const Format s8 = Format::Signed(7, 0), u8 = Format::Unsigned(8, 0);
  for (const Format& f : {s8, u8}) {
    ExpectFormula(Cycles("mpp", f, f, "add", [&](auto& a, auto& b) { return Add(a, b, f); }), 25, "add8");
    ExpectFormula(Cycles("mpp", f, f, "mul", [&](auto& a, auto& b) { return Mul(a, b, f); }), 88, "mul8");
  }
  EXPECT_NEAR(16384 / (25 * 100e-9) / 1e6, 6553, 1);
  EXPECT_NEAR(16384 / (88 * 100e-9) / 1e6, 1861, 1);
  for (int n = 1; n <= 40; ++n) {
    const Format f = Format::Signed(n - 1, 0);
    ExpectFormula(Cycles("mpp", f, f, "add", [&](auto& a, auto& b) { return Add(a, b, f); }),
                  3 * n + 1, "mpp add " + std::to_string(n));
    ExpectFormula(Cycles("mpp", f, f, "mul", [&](auto& a, auto& b) { return Mul(a, b, f); }),
                  n * n + 3 * n, "mpp mul " + std::to_string(n));
  }
}

TEST(BitserialCycles, WaveTracerClosedForms) {
  for (int n = 1; n <= 64; ++n) {
    const Format f = Format::Signed(n - 1, 0);
    const std::string tag = " n=" + std::to_string(n);
    ExpectFormula(Cycles("wavetracer", f, f, "add", [&](auto& a, auto& b) { return Add(a, b, f); }),
                  4 * n + 2, "add" + tag);
    ExpectFormula(Cycles("wavetracer", f, f, "sub", [&](auto& a, auto& b) { return Sub(a, b, f); }),
                  4 * n + 2, "sub" + tag);
    ExpectFormula(Cycles("wavetracer", f, f, "mul", [&](auto& a, auto& b) { return Mul(a, b, f); }),
                  4 * n * n + 5 * n, "mul" + tag);
    ExpectFormula(Cycles("wavetracer", f, f, "compare", [&](auto& a, auto& b) { return a < b; }),
                  3 * n + 3, "compare" + tag);
  }
  // Operands in external memory: each read costs readExternal (2) instead of 1.
  Machine m(Profile("wavetracer"));
  const Format f = Format::Signed(15, 0);
  Multi a(m, f, "a", Space::External), b(m, f, "b", Space::External);
  Multi r = Add(a, b, f);
  ExpectFormula(m.Report().OpCycles("add"), 4 * 16 + 2 + 2 * 16, "add external operands");
}

TEST(BitserialCycles, MulUniCostFollowsTheConstantsOneBits) {
  const Format c8 = Format::Signed(7, 0);
  for (int n : {8, 12, 20}) {
    const Format f = Format::Signed(n - 1, 0);
    for (int64_t c : {0x01, 0x03, 0x7f, 0x55, -1}) {
      fixed::Fixed k{c8, c};
      const int ones = static_cast<int>(std::popcount(static_cast<uint64_t>(c) & 0xff));
      auto op = [&](auto& a, auto&) { return Mul(a, Uni{k}, f); };
      ExpectFormula(Cycles("wavetracer", f, f, "mulUni", op), ones * (4 * n + 1) + 2 * n + 8,
                    "wavetracer mulUni n=" + std::to_string(n) + " c=" + std::to_string(c));
      ExpectFormula(Cycles("mpp", f, f, "mulUni", op), ones * (n + 1) + n,
                    "mpp mulUni n=" + std::to_string(n) + " c=" + std::to_string(c));
    }
  }
}

TEST(BitserialCycles, CountsDoNotDependOnDataAndScaleWithLayers) {
  const Format fa = Format::Signed(9, 6), fb = Format::Unsigned(4, 9), out = Format::Signed(5, 7);
  const fixed::Policy p{fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate};
  auto mul = [&](auto& a, auto& b) { return Mul(a, b, out, p); };
  auto add = [&](auto& a, auto& b) { return Add(a, b, out, p); };
  for (const char* prof : {"wavetracer", "mpp"}) {
    EXPECT_EQ(Cycles(prof, fa, fb, "mul", mul, 1), Cycles(prof, fa, fb, "mul", mul, 2));
    EXPECT_EQ(Cycles(prof, fa, fb, "add", add, 1), Cycles(prof, fa, fb, "add", add, 99));
  }
  // 384x384 virtual PEs = 18 layers, each charged the one-layer cycles.
  const double one = Cycles("wavetracer", fa, fb, "mul", mul, 1);
  EXPECT_EQ(Cycles("wavetracer", fa, fb, "mul", mul, 1, 384 * 384), 18 * one);
}

TEST(BitserialCycles, ProfilesAreDataAndCheckedByName) {
  MachineProfile p = Profile("wavetracer");
  p.Override("readInternal=3");
  EXPECT_EQ(p.Cost(MicroOp::ReadInternal), 3);
  EXPECT_THROW(p.Override("warpDrive=1"), UserError);
  EXPECT_THROW(p.Override("readInternal=fast"), UserError);
  EXPECT_THROW(Profile("cray"), UserError);
  std::map<std::string, std::pair<double, std::string>> table = {
      {"clockHz", {1e6, ""}}, {"physicalPes", {64, ""}}, {"internalBitsPerPe", {8, ""}},
      {"externalBitsPerPe", {8, ""}}};
  try {
    ProfileFromTable("partial", table);
    FAIL() << "a profile without micro-op costs was accepted";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("'readInternal'"), std::string::npos) << e.what();
  }
  // Every assumed WaveTracer cost says so.
  MachineProfile wt = Profile("wavetracer");
  for (int i = 0; i < kMicroOpCount; ++i)
    EXPECT_NE(wt.note[i].find("assumed"), std::string::npos) << MicroOpName(static_cast<MicroOp>(i));
}

}  // namespace
}  // namespace zephyr::bitserial

#include "hosts/cmd/command.h"

namespace zephyr::bitserial {
namespace {

TEST(BitserialCycles, CyclesCommandPrintsBatchersFigures) {
  const char* add[] = {"zephyr", "cycles", "--profile", "mpp", "--op", "add", "--bits", "8"};
  testing::internal::CaptureStdout();
  EXPECT_EQ(RunZephyr(8, add), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find(": 25 cycles per layer"), std::string::npos);
  const char* mul[] = {"zephyr", "cycles", "--profile", "mpp", "--op", "mul", "--bits", "8", "--json"};
  testing::internal::CaptureStdout();
  EXPECT_EQ(RunZephyr(9, mul), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find("\"cycles\": 88.0"), std::string::npos);
  const char* bad[] = {"zephyr", "cycles", "--op", "teleport"};
  testing::internal::CaptureStderr();
  EXPECT_NE(RunZephyr(4, bad), 0);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'teleport'"), std::string::npos);
}

}  // namespace
}  // namespace zephyr::bitserial
