// Hardware-fidelity tests 2 and 3: cycle counts equal each op's closed form (docs/
// bitserial.md) at N and not N-1, do not depend on the data, scale with the layers, and the
// MPP profile reproduces Batcher's published figures from the same engine code.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <random>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "tests/bitserial/closed_forms.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;
using fixed::Policy;
using testutil::ChargedMicroOps;
using testutil::Cycles;
using testutil::ExpectFormula;
using testutil::kPolicies;

TEST(BitserialCycles, MppReproducesBatcher1980) {
  // 8-bit add = 25 cycles (6553 MOPS on 16384 PEs at 100 ns), 8x8 multiply = 88 (1861 MOPS).
  const Format s8 = Format::Signed(7, 0), u8 = Format::Unsigned(8, 0);
  for (const Format& f : {s8, u8}) {
    ExpectFormula(Cycles("mpp", f, f, "add", [&](auto& a, auto& b) { return Add(a, b, f); }), 25,
                  "add8");
    ExpectFormula(Cycles("mpp", f, f, "mul", [&](auto& a, auto& b) { return Mul(a, b, f); }), 88,
                  "mul8");
  }
  // The published rates follow from the engine's cycles and the profile's geometry and clock
  // (16384 PEs at 100 ns): MOPS = PEs / (cycles / clock).
  const MachineProfile mpp = Profile("mpp");
  auto mops = [&](double cycles) { return mpp.physicalPes / (cycles / mpp.clockHz) / 1e6; };
  EXPECT_NEAR(mops(Cycles("mpp", s8, s8, "add", [&](auto& a, auto& b) { return Add(a, b, s8); })),
              6553, 1);
  EXPECT_NEAR(mops(Cycles("mpp", s8, s8, "mul", [&](auto& a, auto& b) { return Mul(a, b, s8); })),
              1861, 1);
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
  Multi a(m, f, "a", Space::kExternal), b(m, f, "b", Space::kExternal);
  Multi r = Add(a, b, f);
  ExpectFormula(m.Report().OpCycles("add"), 4 * 16 + 2 + 2 * 16, "add external operands");
}

// Every operation's micro-op counts equal its closed form (tests/bitserial/closed_forms.h,
// from docs/bitserial.md) under each of the four rounding/overflow policies, with the
// operands and the result in internal or external memory (all eight placements), for
// results that drop 0..3 fraction bits (Nearest's rounding pass; overflow possible or not).
TEST(BitserialCycles, ClosedFormsUnderEveryPolicyAndPlacement) {
  const Space I = Space::kInternal, E = Space::kExternal;
  const fixed::Fixed constant = fixed::Fixed{Format::Signed(7, 0), 0x35};  // 4 one bits
  int checked = 0;
  for (int n : {8, 13}) {
    const Format f = closed::Operand(n), integer = Format::Signed(n - 1, 0);
    for (const Policy& p : kPolicies)
      for (Space sa : {I, E})
        for (Space sb : {I, E})
          for (Space so : {I, E}) {
            const std::string where =
                fmt::format("n={} rounding {} overflow {} a {} b {} out {}", n, int(p.rounding),
                            int(p.overflow), SpaceName(sa), SpaceName(sb), SpaceName(so));
            // Runs `op` on fresh operands placed in sa/sb (the result lands in so: internal
            // memory is filled first for an external result) and compares the micro-ops.
            auto check = [&](const char* name, const Format& fa, const closed::Counts& want,
                             const std::function<void(Multi&, Multi&, Multi&)>& op) {
              Machine m(Profile("wavetracer"));
              Multi a(m, fa, "a", sa), b(m, fa, "b", sb), mask(m, BoolFormat(), "mask", sb);
              std::mt19937_64 rng(n);
              std::vector<int64_t> ra(m.VirtualPes()), rb(m.VirtualPes()), rm(m.VirtualPes());
              for (size_t i = 0; i < ra.size(); ++i)
                ra[i] = static_cast<int64_t>(rng()) >> (64 - n),
                rb[i] = static_cast<int64_t>(rng()) >> (64 - n), rm[i] = rng() & 1;
              a.LoadRaw(ra), b.LoadRaw(rb), mask.LoadRaw(rm);
              PeMemory& mem = m.Memory();
              const int64_t free = mem.Capacity(I) - mem.Used(I);
              if (so == E && free > 0) mem.Allocate("filler", free, I);
              op(a, b, mask);
              EXPECT_EQ(ChargedMicroOps(m, name), want.n)
                  << name << " " << fa.Name() << " " << where;
              ++checked;
            };
            for (int drop = 0; drop <= 3; ++drop) {
              const std::string d = " drop " + std::to_string(drop);
              const Format out = closed::Out(n, closed::kFrac - drop);
              check("add", f, closed::AddSub(n, drop, p, sa, sb, so),
                    [&](auto& a, auto& b, auto&) { Multi r = Add(a, b, out, p); });
              check("sub", f, closed::AddSub(n, drop, p, sa, sb, so),
                    [&](auto& a, auto& b, auto&) { Multi r = Sub(a, b, out, p); });
              check("neg", f, closed::Neg(n, drop, p, sa, so),
                    [&](auto& a, auto&, auto&) { Multi r = Neg(a, out, p); });
              check("abs", f, closed::Abs(n, drop, p, sa, so),
                    [&](auto& a, auto&, auto&) { Multi r = Abs(a, out, p); });
              check("min", f, closed::MinMax(n, drop, p, sa, sb, so),
                    [&](auto& a, auto& b, auto&) { Multi r = Min(a, b, out, p); });
              check("max", f, closed::MinMax(n, drop, p, sa, sb, so),
                    [&](auto& a, auto& b, auto&) { Multi r = Max(a, b, out, p); });
              check("select", f, closed::Select(n, drop, p, sa, sb, so),
                    [&](auto& a, auto& b, auto& mask) { Multi r = Select(mask, a, b, out, p); });
              check("convert", f, closed::Shift(n, drop, 0, p, sa, so),
                    [&](auto& a, auto&, auto&) { Multi r = Convert(a, out, p); });
              for (int s : {1, 2})
                check("shift", f, closed::Shift(n, drop, s, p, sa, so),
                      [&](auto& a, auto&, auto&) { Multi r = Shift(a, s, out, p); });
              const Format mulOut = closed::MulOut(n, drop), uniOut = closed::MulUniOut(n, drop);
              check("mul", f, closed::Mul(n, drop, p, sa, sb, so, false),
                    [&](auto& a, auto& b, auto&) { Multi r = Mul(a, b, mulOut, p); });
              check("square", f, closed::Mul(n, drop, p, sa, sb, so, true),
                    [&](auto& a, auto&, auto&) { Multi r = Square(a, mulOut, p); });
              check("mulUni", f, closed::MulUni(n, 4, drop, p, sa, so),
                    [&](auto& a, auto&, auto&) { Multi r = Mul(a, Uni{constant}, uniOut, p); });
            }
            check("compare", f, closed::Compare(n, sa, sb, so),
                  [&](auto& a, auto& b, auto&) { Multi r = a < b; });
            check("div", integer, closed::Div(n, p, sa, sb, so),
                  [&](auto& a, auto& b, auto&) { Multi r = Div(a, b, integer, p); });
            const int h = n / 2;
            check("sqrt", integer, closed::Sqrt(n, n, p, sa, so),
                  [&](auto& a, auto&, auto&) { Multi r = Sqrt(a, integer, p); });
            check("sqrt", integer, closed::Sqrt(n, h - 1, p, sa, so),
                  [&](auto& a, auto&, auto&) { Multi r = Sqrt(a, Format::Signed(h - 2, 0), p); });
            if (so == sa) {  // reductions have no multi result; a mesh shift writes in a's space
              check("reduceSum", f, closed::Reduce(n, false, sa),
                    [&](auto& a, auto&, auto&) { ReduceSum(a); });
              check("reduceMax", f, closed::Reduce(n, true, sa),
                    [&](auto& a, auto&, auto&) { ReduceMax(a); });
              check("reduceMin", f, closed::Reduce(n, true, sa),
                    [&](auto& a, auto&, auto&) { ReduceMin(a); });
              check("meshShift", f, closed::MeshShift(n, 3, sa),
                    [&](auto& a, auto&, auto&) { Multi r = MeshShift(a, 1, -3); });
            }
          }
  }
  EXPECT_GT(checked, 2 * 4 * 8 * 40);
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

// Whatever the operands hold (zeros, all ones, the extremes, random), the engine charges
// exactly the closed form's micro-ops (an independent count, tests/bitserial/closed_forms.h),
// and on 18 layers 18 times as many.
TEST(BitserialCycles, CountsDoNotDependOnDataAndScaleWithLayers) {
  const Policy p{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  const int n = 12;
  const Format f = closed::Operand(n);
  for (int data = 0; data < 5; ++data) {
    Machine m(Profile("wavetracer"));
    std::mt19937_64 rng(data);
    std::vector<int64_t> ra(m.VirtualPes()), rb(m.VirtualPes());
    for (size_t i = 0; i < ra.size(); ++i) {
      const int64_t r1 = static_cast<int64_t>(rng()) >> (64 - n),
                    r2 = static_cast<int64_t>(rng()) >> (64 - n);
      const int64_t fixedValue[] = {0, -1, f.MaxRaw().convert_to<int64_t>(),
                                    f.MinRaw().convert_to<int64_t>()};
      ra[i] = data < 4 ? fixedValue[data] : r1;
      rb[i] = data < 4 ? fixedValue[3 - data] : r2;
    }
    Multi a(m, f, "a"), b(m, f, "b");
    a.LoadRaw(ra), b.LoadRaw(rb);
    const Space I = Space::kInternal;
    Multi r1 = Mul(a, b, closed::MulOut(n, 2), p);
    Multi r2 = Add(a, b, closed::Out(n, closed::kFrac - 1), p);
    EXPECT_EQ(ChargedMicroOps(m, "mul"), closed::Mul(n, 2, p, I, I, I, false).n) << "data " << data;
    EXPECT_EQ(ChargedMicroOps(m, "add"), closed::AddSub(n, 1, p, I, I, I).n) << "data " << data;
  }
  // 384x384 virtual PEs = 18 layers, each charged the one-layer micro-ops.
  Machine m(Profile("wavetracer"), 384 * 384);
  Multi a(m, f, "a"), b(m, f, "b");
  Multi r = Mul(a, b, closed::MulOut(n, 2), p);
  closed::Counts want =
      closed::Mul(n, 2, p, Space::kInternal, Space::kInternal, Space::kInternal, false);
  for (auto& [op, k] : want.n) k *= 18;
  EXPECT_EQ(ChargedMicroOps(m, "mul"), want.n);
}

TEST(BitserialCycles, ProfilesAreDataAndCheckedByName) {
  MachineProfile p = Profile("wavetracer");
  p.Override("readInternal=3");
  EXPECT_EQ(p.Cost(MicroOp::kReadInternal), 3);
  EXPECT_THROW(p.Override("warpDrive=1"), UserError);
  EXPECT_THROW(p.Override("readInternal=fast"), UserError);
  // Issue 11: every value a flag can give is checked: no infinite cost or clock, no clock of
  // 0 Hz, memory sizes whole and in range (1e30 bits once became a negative size).
  for (const char* bad : {"readInternal=inf", "clockHz=0", "clockHz=inf", "internalBitsPerPe=1e30",
                          "externalBitsPerPe=2.5", "internalBitsPerPe=-1", "readInternal=nan"})
    EXPECT_THROW(p.Override(bad), UserError) << bad;
  p.Override("externalBitsPerPe=4096");
  EXPECT_EQ(p.externalBitsPerPe, 4096);
  EXPECT_THROW(Profile("cray"), UserError);
  // A malformed profile file (a missing cost, a layer that is no whole number of kernel
  // vectors, ...) is refused by its reader: tests/bitserial/profile_test.cpp.
  // Every assumed WaveTracer cost says so.
  MachineProfile wt = Profile("wavetracer");
  for (int i = 0; i < kMicroOpCount; ++i)
    EXPECT_NE(wt.note[i].find("assumed"), std::string::npos)
        << MicroOpName(static_cast<MicroOp>(i));
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
  EXPECT_NE(testing::internal::GetCapturedStdout().find(": 25 cycles per layer"),
            std::string::npos);
  const char* mul[] = {"zephyr", "cycles", "--profile", "mpp",   "--op",
                       "mul",    "--bits", "8",         "--json"};
  testing::internal::CaptureStdout();
  EXPECT_EQ(RunZephyr(9, mul), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find("\"cycles\": 88.0"), std::string::npos);
  const char* bad[] = {"zephyr", "cycles", "--op", "teleport"};
  testing::internal::CaptureStderr();
  EXPECT_NE(RunZephyr(4, bad), 0);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'teleport'"), std::string::npos);
}

// `zephyr cycles` passes --rounding, --overflow, --frac and --external to the engine: its
// figure equals the engine's own for the same operation (div, 16 bits, 8 fraction
// bits, nearest: 2899 cycles on the WaveTracer).
TEST(BitserialCycles, CyclesCommandFollowsPolicyAndPlacement) {
  const Format f = Format::Signed(7, 8);
  for (const char* op : {"add", "mul", "div", "sqrt"})
    for (const Policy& p : testutil::kPolicies)
      for (bool external : {false, true}) {
        std::vector<std::string> args = {
            "zephyr",     "cycles",
            "--op",       op,
            "--bits",     "16",
            "--frac",     "8",
            "--rounding", p.rounding == fixed::Rounding::kNearest ? "nearest" : "floor",
            "--overflow", p.overflow == fixed::OverflowPolicy::kSaturate ? "saturate" : "wrap",
            "--json"};
        if (external) args.push_back("--external");
        std::vector<const char*> argv;
        for (const std::string& a : args) argv.push_back(a.c_str());
        testing::internal::CaptureStdout();
        ASSERT_EQ(RunZephyr(int(argv.size()), argv.data()), 0);
        const auto j = nlohmann::json::parse(testing::internal::GetCapturedStdout());
        Machine m(Profile("wavetracer"));
        const std::optional<Space> s =
            external ? std::optional<Space>(Space::kExternal) : std::nullopt;
        Multi a(m, f, "a", s), b(m, f, "b", s);
        const std::string name = op;
        Multi r = name == "add"   ? Add(a, b, f, p)
                  : name == "mul" ? Mul(a, b, f, p)
                  : name == "div" ? Div(a, b, f, p)
                                  : Sqrt(a, f, p);
        EXPECT_EQ(j["cycles"].get<double>(), m.Report().OpCycles(name))
            << op << " rounding " << int(p.rounding) << " overflow " << int(p.overflow)
            << " external " << external;
        if (name == "div" && p.rounding == fixed::Rounding::kNearest && !external &&
            p.overflow == fixed::OverflowPolicy::kWrap) {
          EXPECT_EQ(j["cycles"].get<double>(), 2899);
        }
      }
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

// A uni operand of a division costs nothing to read and brings its magnitude from the host
// (docs/bitserial.md): Div(uni a, b) charges what Div(a, b) with a in internal memory
// charges, less a's magnitude pass (one sign read and flag op, then n reads, ALU steps and
// writes) and less the n reads of |a|'s bits — for signed and unsigned dividends, every policy.
TEST(BitserialCycles, AUniDividendCostsItsMultiTwinLessItsReadsAndMagnitude) {
  int checked = 0;
  for (int n : {4, 8, 13, 16})
    for (bool isSigned : {true, false})
      for (const Policy& p : kPolicies) {
        const Format f = isSigned ? Format::Signed(n - 1, 0) : Format::Unsigned(n, 0);
        const int64_t raw = isSigned ? -(int64_t(1) << (n - 2)) + 3 : (int64_t(1) << (n - 1)) + 3;
        const fixed::Fixed value{f, raw};
        Machine mm(Profile("wavetracer")), mu(Profile("wavetracer"));
        Multi am(mm, f, "a", Space::kInternal), bm(mm, f, "b", Space::kInternal),
            bu(mu, f, "b", Space::kInternal);
        std::vector<int64_t> ra(mm.VirtualPes(), raw), rb(mm.VirtualPes());
        for (size_t i = 0; i < rb.size(); ++i) rb[i] = int64_t(i % 7) + 1;
        am.LoadRaw(ra), bm.LoadRaw(rb), bu.LoadRaw(rb);
        Multi qm = Div(am, bm, f, p);
        Multi qu = Div(Uni{value}, bu, f, p);
        std::map<std::string, int64_t> want = ChargedMicroOps(mm, "div");
        const int w = f.Width();
        if (isSigned) {  // a's magnitude pass
          want["readInternal"] -= 1 + w;
          want["flagOp"] -= 1;
          want["aluStep"] -= w;
          want["writeInternal"] -= w;
        }
        std::map<std::string, int64_t> got = ChargedMicroOps(mu, "div");
        // a's bit reads (each from internal memory): what remains of readInternal above the
        // uni run are the dividend's reads — one per quotient step's bit brought down, and for
        // a signed dividend its sign twice more (the floor correction's test).
        const int64_t aReads = want["readInternal"] - got["readInternal"];
        EXPECT_GE(aReads, w - 1) << f.Name();
        EXPECT_LE(aReads, w + (isSigned ? 2 : 1)) << f.Name();
        want["readInternal"] = got["readInternal"];
        for (auto it = want.begin(); it != want.end();)
          it = it->second == 0 ? want.erase(it) : std::next(it);
        for (auto it = got.begin(); it != got.end();)
          it = it->second == 0 ? got.erase(it) : std::next(it);
        EXPECT_EQ(got, want) << f.Name() << " rounding " << int(p.rounding) << " overflow "
                             << int(p.overflow);
        ++checked;
      }
  EXPECT_EQ(checked, 4 * 2 * 4);
}

// Reductions over no active PE (multi.h): Max gives the format's smallest value, Min its
// largest, Or 0, Sum 0, in signed and unsigned formats.
TEST(BitserialReduce, NoActivePeGivesTheDocumentedIdentity) {
  for (const Format f : {Format::Signed(7, 4), Format::Unsigned(9, 0), Format::Signed(0, 15)}) {
    Machine m(Profile("wavetracer"));
    Multi a(m, f, "a", Space::kInternal), none(m, BoolFormat(), "none", Space::kInternal);
    std::vector<int64_t> raw(m.VirtualPes(), 1), zero(m.VirtualPes(), 0);
    a.LoadRaw(raw), none.LoadRaw(zero);
    Where(none, [&] {
      EXPECT_TRUE(ReduceMax(a).raw == f.MinRaw()) << f.Name();
      EXPECT_TRUE(ReduceMin(a).raw == f.MaxRaw()) << f.Name();
      EXPECT_TRUE(ReduceOr(a).raw == 0) << f.Name();
      EXPECT_TRUE(ReduceSum(a).raw == 0) << f.Name();
    });
    // And with every PE active, the values themselves.
    EXPECT_TRUE(ReduceMax(a).raw == 1) << f.Name();
    EXPECT_TRUE(ReduceMin(a).raw == 1) << f.Name();
  }
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

// A sum of program runs (CycleReport::Add, the SIMD pass's array passes): every figure is
// the runs' figures added, the layers are listed run after run with their run, each run is
// kept whole, and a one-run report is exactly its run.
TEST(BitserialCycleReport, AddSumsRunsAndKeepsEach) {
  const MachineProfile profile = Profile("wavetracer");
  MicroOpCounts a, b;
  a.Add(MicroOp::kAluStep, 7), a.Add(MicroOp::kReadInternal, 3);
  b.Add(MicroOp::kHostPlane, 2), b.Add(MicroOp::kAluStep, 5);
  CycleReport first(&profile, 3), second(&profile, 2);
  first.Charge("add", a), first.Charge("add", a);
  second.Charge("add", a), second.Charge("hostRead", b);
  CycleReport sum;
  sum.Add(first);
  EXPECT_EQ(sum.Json(), first.Json()) << "one run: exactly its report";
  sum.Add(second);
  ASSERT_EQ(sum.Runs(), 2);
  EXPECT_EQ(sum.Layers(), 5);
  EXPECT_EQ(sum.TotalCycles(), first.TotalCycles() + second.TotalCycles());
  EXPECT_EQ(sum.ModelledSeconds(), first.ModelledSeconds() + second.ModelledSeconds());
  for (int c = 0; c < kCycleClassCount; ++c)
    EXPECT_EQ(sum.ClassCycles(CycleClass(c)),
              first.ClassCycles(CycleClass(c)) + second.ClassCycles(CycleClass(c)));
  EXPECT_EQ(sum.OpCalls("add"), 3);
  EXPECT_EQ(sum.OpCalls("hostRead"), 1);
  EXPECT_EQ(sum.OpCycles("add"), first.OpCycles("add") + second.OpCycles("add"));
  EXPECT_EQ(sum.Run(0).Json(), first.Json());
  EXPECT_EQ(sum.Run(1).Json(), second.Json());
  const nlohmann::json j = sum.Json();
  EXPECT_EQ(j["layers"], 5);
  EXPECT_EQ(j["totalCycles"].get<double>(), sum.TotalCycles());
  ASSERT_EQ(j["byLayer"].size(), 5u);
  EXPECT_EQ(j["byLayer"][3]["layer"], 3);
  EXPECT_EQ(j["byLayer"][3]["pass"], 1);
  EXPECT_EQ(j["byLayer"][3]["cycles"].get<double>(), second.LayerCycles());
  EXPECT_EQ(j["byOp"]["add"]["calls"], 3);
  EXPECT_EQ(j["byOp"]["add"]["microOps"]["aluStep"].get<int64_t>(), 7 * 2 * 3 + 7 * 2);
  EXPECT_EQ(j["byOp"]["hostRead"]["cycles"].get<double>(), second.OpCycles("hostRead"));
}

}  // namespace
}  // namespace zephyr::bitserial
