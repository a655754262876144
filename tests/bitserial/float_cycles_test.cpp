// The cycle charges of the bit-serial floating point (bitserial/float.h) against their
// closed forms (tests/bitserial/closed_forms.h, namespace fp, written from docs/float.md):
// every operation, micro-op by micro-op, in every format the engine allows (e2m1 .. e11m52,
// with and without subnormals), at the boundary formats with the operands in either memory
// or uni and the result in either memory, on both profiles; the conversions for fixed sides
// from 1 to 128 bits under every policy; and the cycle table of docs/float.md and the MPP's
// published float rows (Batcher 1980) as numbers.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/float.h"
#include "tests/bitserial/closed_forms.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using closed::At;
using fixed::FloatFormat;
using testutil::ChargedMicroOps;
using testutil::kPolicies;

// Where an operand is: a multi in internal or external memory, or a uni (UniFloat).
enum class Place { kInternal, kExternal, kUni };
At AtOf(Place p) {
  return p == Place::kInternal ? At::kInternal : p == Place::kExternal ? At::kExternal : At::kConst;
}
const char* NameOf(Place p) {
  return p == Place::kInternal ? "internal" : p == Place::kExternal ? "external" : "uni";
}

// Every format the engine allows: 2 <= e <= 11, 1 <= m <= 52, 1 + e + m <= 64.
std::vector<FloatFormat> AllFormats() {
  std::vector<FloatFormat> r;
  for (int e = 2; e <= 11; ++e)
    for (int m = 1; m <= 52 && 1 + e + m <= 64; ++m)
      for (bool sub : {true, false}) r.push_back({e, m, sub});
  return r;
}

// The boundary formats: the narrowest exponent and significand (e2m1), each at its widest
// with the other at its narrowest (e2m52, e11m1), IEEE binary16/32/64 (e11m52 is also the
// widest word), and the formats where a stage count changes (p + 3 = 8 | 9: e5m4, e5m5;
// 2p = 32 | 34: e8m15, e8m16), each with and without subnormals.
std::vector<FloatFormat> BoundaryFormats() {
  std::vector<FloatFormat> r;
  for (auto [e, m] : {std::pair{2, 1},
                      {2, 52},
                      {11, 1},
                      {5, 10},
                      {8, 23},
                      {11, 52},
                      {5, 4},
                      {5, 5},
                      {8, 15},
                      {8, 16}})
    for (bool sub : {true, false}) r.push_back({e, m, sub});
  return r;
}

// A one-layer machine (64 PEs loaded) with the operands placed; `filler` fills what is left
// of internal memory so that the result (and ftofixed's frame) lands in external memory.
struct Rig {
  Machine m;
  explicit Rig(const std::string& profile) : m(Profile(profile), 64) {}
  MultiFloat Operand(const FloatFormat& f, Place p, const char* name, uint64_t seed) {
    MultiFloat x(m, f, name, p == Place::kExternal ? Space::kExternal : Space::kInternal);
    std::vector<uint64_t> v(64);
    for (auto& b : v) b = (seed = seed * 6364136223846793005ULL + 1442695040888963407ULL) >> 3;
    x.Load(v);
    return x;
  }
  UniFloat Uni(const FloatFormat& f) { return {f, f.Infinity(false) >> 1}; }
  void ResultIn(Space so) {
    PeMemory& mem = m.Memory();
    const int64_t free = mem.Capacity(Space::kInternal) - mem.Used(Space::kInternal);
    if (so == Space::kExternal && free > 0) mem.Allocate("filler", free, Space::kInternal);
    m.Report().Clear();
  }
};

// The engine's counts for one float op: `op` is fadd fsub fmul fdiv fsqrt fmin fmax fless
// flessEqual fequal (a, b placed as given; sqrt reads a only).
std::map<std::string, int64_t> Engine(const std::string& profile, const std::string& op,
                                      const FloatFormat& f, Place pa, Place pb, Space so,
                                      double* cycles = nullptr) {
  Rig rig(profile);
  std::optional<MultiFloat> a, b;
  if (pa != Place::kUni) a = rig.Operand(f, pa, "a", 1);
  if (pb != Place::kUni) b = rig.Operand(f, pb, "b", 2);
  const UniFloat u = rig.Uni(f);
  rig.ResultIn(so);
  // Binary ops with either side uni (not both).
  auto bin = [&](auto fn) {
    if (pa == Place::kUni)
      fn(u, *b);
    else if (pb == Place::kUni)
      fn(*a, u);
    else
      fn(*a, *b);
  };
  std::string charged = op;
  if (op == "fadd")
    bin([](auto& x, auto& y) { Add(x, y); });
  else if (op == "fsub")
    bin([](auto& x, auto& y) { Sub(x, y); });
  else if (op == "fmul")
    bin([](auto& x, auto& y) { Mul(x, y); });
  else if (op == "fdiv")
    bin([](auto& x, auto& y) { Div(x, y); });
  else if (op == "fmin")
    bin([](auto& x, auto& y) { Min(x, y); });
  else if (op == "fmax")
    bin([](auto& x, auto& y) { Max(x, y); });
  else if (op == "fsqrt")
    Sqrt(*a);
  else {
    charged = "fcompare";
    if (op == "fless")
      bin([](auto& x, auto& y) { Less(x, y); });
    else if (op == "flessEqual")
      bin([](auto& x, auto& y) { LessEqual(x, y); });
    else if (op == "fequal")
      bin([](auto& x, auto& y) { Equal(x, y); });
    else
      ADD_FAILURE() << op;
  }
  if (cycles) *cycles = rig.m.Report().OpCycles(charged);
  return ChargedMicroOps(rig.m, charged);
}

closed::Counts Form(const std::string& op, const FloatFormat& f, Place pa, Place pb, Space so) {
  namespace fp = closed::fp;
  const At a = AtOf(pa), b = AtOf(pb), o = closed::Of(so);
  if (op == "fadd") return fp::AddSub(f, a, b, o, false);
  if (op == "fsub") return fp::AddSub(f, a, b, o, true);
  if (op == "fmul") return fp::Mul(f, a, b, o);
  if (op == "fdiv") return fp::Div(f, a, b, o);
  if (op == "fsqrt") return fp::Sqrt(f, a, o);
  if (op == "fmin") return fp::MinMax(f, a, b, o, false);
  if (op == "fmax") return fp::MinMax(f, a, b, o, true);
  if (op == "fless") return fp::Compare(f, a, b, o, fp::CompareKind::kLess);
  if (op == "flessEqual") return fp::Compare(f, a, b, o, fp::CompareKind::kLessEqual);
  return fp::Compare(f, a, b, o, fp::CompareKind::kEqual);
}

// The cycles of counts on a profile: each micro-op's count times its cost.
double CyclesOf(const closed::Counts& c, const MachineProfile& profile) {
  double total = 0;
  for (int i = 0; i < kMicroOpCount; ++i) {
    auto it = c.n.find(MicroOpName(static_cast<MicroOp>(i)));
    if (it != c.n.end()) total += it->second * profile.cost[i];
  }
  return total;
}

const std::vector<std::string> kOps = {"fadd", "fsub", "fmul",  "fdiv",       "fsqrt",
                                       "fmin", "fmax", "fless", "flessEqual", "fequal"};

TEST(BitserialFloatCycles, EveryOpEqualsItsClosedFormInEveryFormat) {
  int checked = 0;
  for (const FloatFormat& f : AllFormats())
    for (const std::string& op : kOps) {
      const auto want = Form(op, f, Place::kInternal, Place::kInternal, Space::kInternal);
      EXPECT_EQ(Engine("wavetracer", op, f, Place::kInternal, Place::kInternal, Space::kInternal),
                want.n)
          << op << " " << f.Name();
      ++checked;
    }
  EXPECT_EQ(checked, 1040 * 10);
}

// Each operand in internal or external memory or a uni (not both uni), the result in either
// memory (the MPP has no external memory), on both profiles: the micro-ops and the cycles
// they cost.
TEST(BitserialFloatCycles, BoundaryFormatsEveryPlacementBothProfiles) {
  int checked = 0;
  for (const std::string profile : {"wavetracer", "mpp"}) {
    const MachineProfile prof = Profile(profile);
    const bool external = prof.externalBitsPerPe > 0;
    std::vector<Place> places = {Place::kInternal, Place::kUni};
    if (external) places.push_back(Place::kExternal);
    for (const FloatFormat& f : BoundaryFormats())
      for (const std::string& op : kOps)
        for (Place pa : places)
          for (Place pb : places)
            for (Space so : {Space::kInternal, Space::kExternal}) {
              if (pa == Place::kUni && pb == Place::kUni) continue;
              if (op == "fsqrt" && (pb != Place::kInternal || pa == Place::kUni)) continue;
              if (so == Space::kExternal && !external) continue;
              const std::string what = fmt::format("{} {} {} a {} b {} out {}", profile, op,
                                                   f.Name(), NameOf(pa), NameOf(pb), SpaceName(so));
              double cycles = 0;
              const auto want = Form(op, f, pa, pb, so);
              EXPECT_EQ(Engine(profile, op, f, pa, pb, so, &cycles), want.n) << what;
              EXPECT_EQ(cycles, CyclesOf(want, prof)) << what;
              ++checked;
            }
  }
  EXPECT_EQ(checked, 3520);
}

// The conversions' engine counts: ftofixed of a (at pa) into `fx` under policy, or
// ffromfixed of a fixed multi of format fx (at pa) into f; the result in `so`.
std::map<std::string, int64_t> EngineConversion(const std::string& profile, bool toFixed,
                                                const FloatFormat& f, const fixed::Format& fx,
                                                fixed::Policy policy, Place pa, Space so,
                                                double* cycles) {
  Rig rig(profile);
  const Space sa = pa == Place::kExternal ? Space::kExternal : Space::kInternal;
  if (toFixed) {
    MultiFloat a = rig.Operand(f, pa, "a", 3);
    rig.ResultIn(so);
    ToFixed(a, fx, policy);
  } else {
    Multi a(rig.m, fx, "a", sa);
    std::vector<int64_t> raw(64);
    for (size_t i = 0; i < raw.size(); ++i)
      raw[i] = static_cast<int64_t>(i * 0x9E3779B97F4A7C15ULL);
    a.LoadRaw(raw);
    rig.ResultIn(so);
    ToFloat(a, f);
  }
  const char* name = toFixed ? "ftofixed" : "ffromfixed";
  *cycles = rig.m.Report().OpCycles(name);
  return ChargedMicroOps(rig.m, name);
}

// Fixed sides of every width 1..maxWidth: unsigned integers and signed ones with w/2
// fraction bits.
std::vector<fixed::Format> FixedSides(int maxWidth) {
  std::vector<fixed::Format> r;
  for (int w = 1; w <= maxWidth; ++w) {
    r.push_back(fixed::Format::Unsigned(w, 0));
    r.push_back(fixed::Format::Signed(w - 1 - w / 2, w / 2));
  }
  return r;
}

// ffromfixed from every fixed width 1..128 (past and short of the p + 2 / p + 3 places the
// significand keeps) and ftofixed into every width up to the frame's limit (wo + p + 3 <=
// 128; all four policies at the narrowest and widest), at the boundary formats, the float
// or fixed operand and the result in either memory, on both profiles.
TEST(BitserialFloatCycles, ConversionsEveryFixedSidePolicyAndPlacement) {
  int checked = 0;
  for (const std::string profile : {"wavetracer", "mpp"}) {
    const MachineProfile prof = Profile(profile);
    const bool external = prof.externalBitsPerPe > 0;
    for (const FloatFormat& f : BoundaryFormats())
      for (Place pa : {Place::kInternal, Place::kExternal})
        for (Space so : {Space::kInternal, Space::kExternal}) {
          if (!external && (pa == Place::kExternal || so == Space::kExternal)) continue;
          // Every width on the WaveTracer with the operand and result internal, a sample
          // elsewhere.
          const bool full =
              profile == "wavetracer" && pa == Place::kInternal && so == Space::kInternal;
          const At a = AtOf(pa);
          for (const fixed::Format& fx : FixedSides(128)) {
            if (!full && fx.Width() % 7 != 1) continue;
            const std::string what = fmt::format("{} ffromfixed {} -> {} a {} out {}", profile,
                                                 fx.Name(), f.Name(), NameOf(pa), SpaceName(so));
            double cycles = 0;
            const auto want = closed::fp::FromFixed(fx, a, f, closed::Of(so));
            EXPECT_EQ(EngineConversion(profile, false, f, fx, {}, pa, so, &cycles), want.n) << what;
            EXPECT_EQ(cycles, CyclesOf(want, prof)) << what;
            ++checked;
          }
          for (const fixed::Format& fx : FixedSides(125 - f.Precision()))
            for (const fixed::Policy& policy : kPolicies) {
              // Every policy at the narrowest and widest sides, one per width between.
              const int w = fx.Width(), widest = 125 - f.Precision();
              if (w > 2 && w < widest && &policy != &kPolicies[w % 4]) continue;
              if (!full && w % 5 != 1 && w != widest) continue;
              const std::string what = fmt::format(
                  "{} ftofixed {} -> {} policy {}/{} a {} out {}", profile, f.Name(), fx.Name(),
                  int(policy.rounding), int(policy.overflow), NameOf(pa), SpaceName(so));
              double cycles = 0;
              const auto want = closed::fp::ToFixed(f, a, fx, policy, so);
              EXPECT_EQ(EngineConversion(profile, true, f, fx, policy, pa, so, &cycles), want.n)
                  << what;
              EXPECT_EQ(cycles, CyclesOf(want, prof)) << what;
              ++checked;
            }
        }
  }
  EXPECT_EQ(checked, 17324);
}

// The cycle table of docs/float.md ("Cycle counts": binary32, operands in internal memory,
// the conversions against s31.0 under the default policy), as `zephyr cycles` counts it
// (FloatOpCycles) and as the closed forms give it, on both profiles.
TEST(BitserialFloatCycles, TheDocsTableOfCycleCounts) {
  const std::map<std::string, std::pair<double, double>> table = {
      {"fadd", {2809, 380}},      {"fsub", {2812, 382}},    {"fmul", {4476, 818}},
      {"fdiv", {7498, 1022}},     {"fsqrt", {4801, 631}},   {"fmin", {375, 243}},
      {"fmax", {375, 243}},       {"fcompare", {185, 115}}, {"ftofixed", {1981, 319}},
      {"ffromfixed", {1586, 133}}};
  const fixed::Format s31 = fixed::Format::Signed(31, 0);
  for (const std::string profile : {"wavetracer", "mpp"}) {
    const MachineProfile prof = Profile(profile);
    const FloatFormat f{8, 23, prof.floatSubnormals};  // --bits 32 on this profile
    EXPECT_EQ(f.Name(), profile == "mpp" ? "e8m23ftz" : "e8m23");
    for (const std::string& op : FloatOpNames()) {
      const double want = profile == "mpp" ? table.at(op).second : table.at(op).first;
      EXPECT_EQ(FloatOpCycles(prof, op, f, Space::kInternal, s31), want) << profile << " " << op;
      namespace fp = closed::fp;
      const At I = At::kInternal;
      const closed::Counts form =
          op == "fcompare"     ? fp::Compare(f, I, I, I, fp::CompareKind::kLess)
          : op == "ftofixed"   ? fp::ToFixed(f, I, s31, {}, Space::kInternal)
          : op == "ffromfixed" ? fp::FromFixed(s31, I, f, I)
                               : Form(op, f, Place::kInternal, Place::kInternal, Space::kInternal);
      EXPECT_EQ(CyclesOf(form, prof), want) << profile << " " << op << " (closed form)";
    }
  }
}

// The MPP's published float rows (Batcher 1980: 32-bit add 430 MOPS, multiply 216 MOPS on
// 16,384 PEs at 100 ns, i.e. 381 and 759 cycles) against docs/float.md's figures: 380 cycles
// (431 MOPS) and 818 (200 MOPS) flush to zero, within 10 % of Batcher's; 436 and 898 with
// IEEE gradual underflow; each also the closed form's cycles.
TEST(BitserialFloatCycles, MppPublishedFloatRows) {
  const MachineProfile mpp = Profile("mpp");
  const FloatFormat ftz{8, 23, false}, ieee{8, 23, true};
  const double pes = mpp.physicalPes, cycle = 1 / mpp.clockHz;
  EXPECT_EQ(pes, 16384);
  EXPECT_EQ(cycle, 100e-9);
  struct Row {
    const char* op;
    double batcherMops, cycles, mops, withSubnormals;
  };
  for (const Row& r : {Row{"fadd", 430, 380, 431, 436}, Row{"fmul", 216, 818, 200, 898}}) {
    const double c = FloatOpCycles(mpp, r.op, ftz);
    EXPECT_EQ(c, r.cycles) << r.op;
    EXPECT_EQ(CyclesOf(Form(r.op, ftz, Place::kInternal, Place::kInternal, Space::kInternal), mpp),
              r.cycles)
        << r.op;
    EXPECT_EQ(std::round(pes / (c * cycle) / 1e6), r.mops) << r.op;  // MOPS, as the docs say
    const double published = pes / (r.batcherMops * 1e6 * cycle);    // Batcher's cycles
    EXPECT_NEAR(c, published, 0.1 * published) << r.op;
    EXPECT_EQ(FloatOpCycles(mpp, r.op, ieee), r.withSubnormals) << r.op;
    EXPECT_EQ(CyclesOf(Form(r.op, ieee, Place::kInternal, Place::kInternal, Space::kInternal), mpp),
              r.withSubnormals)
        << r.op;
  }
}

}  // namespace
}  // namespace zephyr::bitserial
