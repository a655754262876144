// Bit-serial floating point (bitserial/float.h) against the exact reference (fixed/
// float.h), and the reference against the host's IEEE binary32: exhaustive for tiny
// formats, edge-biased random pairs for binary32, on every compiled Highway target.
#include "bitserial/float.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <random>

#include "fixed/check.h"
#include "fixed/float.h"
#include "hosts/cmd/command.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::FloatFormat;
using testutil::ForEachTarget;

// A comparison's 1-bit result read as the low bit of a float pattern (the tests read it
// with At(), which reads every plane of the format: the others are zero).
struct BoolResult {
  Multi bit;
  uint64_t At(int64_t pe) const { return bit.BitAt(0, pe); }
};
struct EngineResult {
  MultiFloat value;
  std::optional<BoolResult> flag;
  EngineResult(MultiFloat v) : value(std::move(v)) {}
  EngineResult(BoolResult b) : flag(std::move(b)) {}
  uint64_t At(int64_t pe) const { return flag ? flag->At(pe) : value.At(pe); }
};
EngineResult AsFloat(Multi bit) { return BoolResult{std::move(bit)}; }

using EngineOp = std::function<EngineResult(const MultiFloat&, const MultiFloat&)>;
using RefOp = std::function<uint64_t(const FloatFormat&, uint64_t, uint64_t)>;

struct NamedOp {
  const char* name;
  EngineOp engine;
  RefOp reference;
};

const std::vector<NamedOp>& BinaryOps() {
  static const std::vector<NamedOp> ops = {
      {"add", [](auto& a, auto& b) { return Add(a, b); }, fixed::FloatAdd},
      {"sub", [](auto& a, auto& b) { return Sub(a, b); }, fixed::FloatSub},
      {"mul", [](auto& a, auto& b) { return Mul(a, b); }, fixed::FloatMul},
      {"div", [](auto& a, auto& b) { return Div(a, b); }, fixed::FloatDiv},
      {"min", [](auto& a, auto& b) { return Min(a, b); }, fixed::FloatMin},
      {"max", [](auto& a, auto& b) { return Max(a, b); }, fixed::FloatMax},
      // sqrt of the first operand (the second is ignored); comparisons as 0/1.
      {"sqrt", [](auto& a, auto&) { return Sqrt(a); },
       [](const FloatFormat& f, uint64_t a, uint64_t) { return fixed::FloatSqrt(f, a); }},
      {"less", [](auto& a, auto& b) { return AsFloat(Less(a, b)); },
       [](const FloatFormat& f, uint64_t a, uint64_t b) -> uint64_t {
         return fixed::FloatLess(f, a, b);
       }},
      {"lessEqual", [](auto& a, auto& b) { return AsFloat(LessEqual(a, b)); },
       [](const FloatFormat& f, uint64_t a, uint64_t b) -> uint64_t {
         return fixed::FloatLessEqual(f, a, b);
       }},
      {"equal", [](auto& a, auto& b) { return AsFloat(Equal(a, b)); },
       [](const FloatFormat& f, uint64_t a, uint64_t b) -> uint64_t {
         return fixed::FloatEqual(f, a, b);
       }},
  };
  return ops;
}

// Runs op on the pairs (one pair per virtual PE) and compares every PE with the reference;
// returns the number of mismatches (the first few are printed).
int64_t Mismatches(const FloatFormat& f, const NamedOp& op, const std::vector<uint64_t>& a,
                   const std::vector<uint64_t>& b) {
  Machine m(Profile("wavetracer"), static_cast<int64_t>(a.size()));
  MultiFloat x(m, f, "a"), y(m, f, "b");
  x.Load(a);
  y.Load(b);
  const EngineResult r = op.engine(x, y);
  int64_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const uint64_t want = op.reference(f, a[i], b[i]), got = r.At(static_cast<int64_t>(i));
    if (got != want && ++bad <= 5)
      ADD_FAILURE() << f.Name() << " " << op.name << " " << std::hex << a[i] << ", " << b[i]
                    << ": got " << got << " want " << want << " (" << m.Kernels().target << ")";
  }
  return bad;
}

std::vector<FloatFormat> TinyFormats() {
  return {{2, 1, true}, {3, 2, true}, {3, 2, false}, {4, 3, true}, {4, 3, false}, {2, 5, true}};
}

TEST(BitserialFloat, ExhaustiveTinyFormatsEveryTarget) {
  ForEachTarget([&] {
    for (const FloatFormat& f : TinyFormats()) {
      std::vector<uint64_t> a, b;
      const uint64_t n = uint64_t{1} << f.Width();
      for (uint64_t i = 0; i < n; ++i)
        for (uint64_t j = 0; j < n; ++j) a.push_back(i), b.push_back(j);
      for (const NamedOp& op : BinaryOps())
        EXPECT_EQ(Mismatches(f, op, a, b), 0) << f.Name() << " " << op.name;
    }
  });
}

// Edge-biased binary32 patterns: special exponents and fractions, near ties, operands of
// nearly equal magnitude (cancellation), and uniform random bits.
std::vector<uint64_t> EdgeBiased(std::mt19937_64& rng, size_t count,
                                 std::vector<uint64_t>* partner) {
  std::vector<uint64_t> a;
  auto pick = [&]() -> uint32_t {
    const uint32_t sign = (rng() & 1) << 31;
    static const uint32_t exps[] = {0, 1, 2, 24, 100, 126, 127, 128, 150, 200, 253, 254, 255};
    static const uint32_t fracs[] = {0, 1, 2, 0x400000, 0x7fffff, 0x7ffffe, 0x3fffff, 0x400001};
    const uint32_t e = rng() % 3 ? static_cast<uint32_t>(rng() % 256) : exps[rng() % 13];
    const uint32_t fr = rng() % 2 ? static_cast<uint32_t>(rng() & 0x7fffff) : fracs[rng() % 8];
    return sign | (e << 23) | fr;
  };
  for (size_t i = 0; i < count; ++i) {
    const uint32_t x = rng() % 4 ? pick() : static_cast<uint32_t>(rng());
    uint32_t y;
    switch (rng() % 5) {
      case 0:
        y = x ^ 0x80000000u ^ static_cast<uint32_t>(rng() % 4);
        break;  // cancellation
      case 1:
        y = (x & 0x80000000u) |
            ((x & 0x7fffffffu) + static_cast<uint32_t>(rng() % 64 << 23) - (32u << 23));
        break;
      case 2:
        y = static_cast<uint32_t>(rng());
        break;
      default:
        y = pick();
        break;
    }
    a.push_back(x);
    partner->push_back(y);
  }
  return a;
}

uint64_t HostBits(float v) {
  if (std::isnan(v)) return FloatFormat::Binary32().CanonicalNaN();
  return std::bit_cast<uint32_t>(v);
}

TEST(BitserialFloat, ReferenceIsTheHostsBinary32) {
  const FloatFormat f = FloatFormat::Binary32();
  std::mt19937_64 rng(7);
  std::vector<uint64_t> b;
  const std::vector<uint64_t> a = EdgeBiased(rng, 100000, &b);
  int64_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const float x = std::bit_cast<float>(static_cast<uint32_t>(a[i]));
    const float y = std::bit_cast<float>(static_cast<uint32_t>(b[i]));
    const std::pair<uint64_t, uint64_t> checks[] = {
        {fixed::FloatAdd(f, a[i], b[i]), HostBits(x + y)},
        {fixed::FloatSub(f, a[i], b[i]), HostBits(x - y)},
        {fixed::FloatMul(f, a[i], b[i]), HostBits(x * y)},
        {fixed::FloatDiv(f, a[i], b[i]), HostBits(x / y)},
        {fixed::FloatSqrt(f, a[i]), HostBits(std::sqrt(x))},
        {fixed::FloatLess(f, a[i], b[i]), x < y},
        {fixed::FloatLessEqual(f, a[i], b[i]), x <= y},
        {fixed::FloatEqual(f, a[i], b[i]), x == y},
    };
    for (auto [ref, host] : checks)
      if (ref != host && ++bad <= 5)
        ADD_FAILURE() << std::hex << a[i] << " " << b[i] << ": ref " << ref << " host " << host;
  }
  EXPECT_EQ(bad, 0);
}

TEST(BitserialFloat, Binary32EdgeBiasedPairs) {
  const FloatFormat f = FloatFormat::Binary32();
  std::mt19937_64 rng(11);
  std::vector<uint64_t> b;
  const std::vector<uint64_t> a = EdgeBiased(rng, 100000, &b);
  for (const NamedOp& op : BinaryOps()) EXPECT_EQ(Mismatches(f, op, a, b), 0) << op.name;
  // Every compiled target on a smaller sample.
  std::vector<uint64_t> b2(b.begin(), b.begin() + 8192);
  const std::vector<uint64_t> a2(a.begin(), a.begin() + 8192);
  ForEachTarget([&] {
    for (const NamedOp& op : BinaryOps()) EXPECT_EQ(Mismatches(f, op, a2, b2), 0) << op.name;
  });
}

TEST(BitserialFloat, CyclesDoNotDependOnTheData) {
  const FloatFormat f = FloatFormat::Binary32();
  for (const NamedOp& op : BinaryOps()) {
    double first = -1;
    for (uint64_t seed : {1, 2, 3}) {
      Machine m(Profile("wavetracer"));
      std::mt19937_64 rng(seed);
      std::vector<uint64_t> va(m.VirtualPes()), vb(m.VirtualPes());
      for (auto& v : va) v = rng() & f.Mask();
      for (auto& v : vb) v = seed == 3 ? 0 : rng() & f.Mask();
      MultiFloat x(m, f, "a"), y(m, f, "b");
      x.Load(va), y.Load(vb);
      m.Report().Clear();
      op.engine(x, y);
      const double c = m.Report().TotalCycles();
      if (first < 0) first = c;
      EXPECT_EQ(c, first) << op.name;
    }
  }
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

TEST(BitserialFloat, MppReproducesBatcher1980FloatRows) {
  // Batcher 1980: 32-bit floating-point add 430 MOPS and multiply 216 MOPS on 16,384 PEs
  // at 100 ns, i.e. 16384 / (430e6 × 100e-9) = 381 and 759 cycles per operation. The
  // format is binary32 as the profile's machine kept it (mpp: flush to zero, assumed).
  const MachineProfile mpp = Profile("mpp");
  const fixed::FloatFormat f{8, 23, mpp.floatSubnormals};
  EXPECT_FALSE(f.subnormals);
  const double add = FloatOpCycles(mpp, "fadd", f), mul = FloatOpCycles(mpp, "fmul", f);
  EXPECT_NEAR(add, 16384 / (430e6 * 100e-9), 0.1 * 381);
  EXPECT_NEAR(mul, 16384 / (216e6 * 100e-9), 0.1 * 759);
  // The IEEE gradual underflow costs more (the denormalising shift before rounding).
  EXPECT_GT(FloatOpCycles(mpp, "fadd", fixed::FloatFormat::Binary32()), add);
}

TEST(BitserialFloat, CyclesCommandPrintsTheMppFloatRows) {
  // The same rows through `zephyr cycles` (--bits 32: binary32 as the profile keeps it).
  for (auto [op, published] : {std::pair{"fadd", 381.0}, std::pair{"fmul", 759.0}}) {
    const char* args[] = {"zephyr", "cycles", "--profile", "mpp",   "--op",
                          op,       "--bits", "32",        "--json"};
    testing::internal::CaptureStdout();
    EXPECT_EQ(RunZephyr(9, args), 0);
    const nlohmann::json j = nlohmann::json::parse(testing::internal::GetCapturedStdout());
    EXPECT_EQ(j["format"], "e8m23ftz");
    EXPECT_NEAR(j["cycles"].get<double>(), published, 0.1 * published) << op;
  }
  const char* bad[] = {"zephyr", "cycles", "--op", "fadd", "--float", "e1m99"};
  testing::internal::CaptureStderr();
  EXPECT_NE(RunZephyr(6, bad), 0);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'e1m99'"), std::string::npos);
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

using testutil::kPolicies;

// Float -> fixed: every value of tiny formats into small fixed formats under every policy,
// and edge-biased binary32 values into s15.16, s31.0 and u8.8: the raw bits and the
// per-PE Overflow / Invalid flags equal fixed::FloatToFixed's.
int64_t ToFixedMismatches(const FloatFormat& f, const std::vector<uint64_t>& values,
                          const fixed::Format& out, const fixed::Policy& policy) {
  Machine m(Profile("wavetracer"), static_cast<int64_t>(values.size()));
  MultiFloat x(m, f, "x");
  x.Load(values);
  const Multi r = ToFixed(x, out, policy);
  int64_t bad = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    fixed::Status st;
    const fixed::Fixed want = fixed::FloatToFixed(f, values[i], out, policy, &st);
    const int64_t pe = static_cast<int64_t>(i);
    const fixed::Fixed got = r.At(pe);
    if ((got.raw != want.raw || m.Overflow(pe) != st.overflow || m.Invalid(pe) != st.invalid) &&
        ++bad <= 5)
      ADD_FAILURE() << f.Name() << " -> " << out.Name() << " " << std::hex << values[i] << std::dec
                    << ": got " << got.raw << " ovf " << m.Overflow(pe) << " inv " << m.Invalid(pe)
                    << ", want " << want.raw << " ovf " << st.overflow << " inv " << st.invalid
                    << " (" << m.Kernels().target << ")";
  }
  return bad;
}

// Fixed -> float: the float's bits equal fixed::FloatFromFixed's.
int64_t ToFloatMismatches(const fixed::Format& in, const std::vector<int64_t>& raw,
                          const FloatFormat& f) {
  Machine m(Profile("wavetracer"), static_cast<int64_t>(raw.size()));
  Multi x(m, in, "x");
  x.LoadRaw(raw);
  const MultiFloat r = ToFloat(x, f);
  int64_t bad = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    const int64_t pe = static_cast<int64_t>(i);
    const uint64_t want = fixed::FloatFromFixed(x.At(pe), f), got = r.At(pe);
    if (got != want && ++bad <= 5)
      ADD_FAILURE() << in.Name() << " -> " << f.Name() << " raw " << raw[i] << std::hex << ": got "
                    << got << " want " << want << " (" << m.Kernels().target << ")";
  }
  return bad;
}

std::vector<fixed::Format> SmallFixed() {
  using fixed::Format;
  return {Format::Signed(3, 2), Format::Unsigned(3, 1), Format::Signed(6, 0), Format::Signed(0, 5),
          Format::Unsigned(0, 4)};
}

TEST(BitserialFloat, ConversionsExhaustiveTinyFormatsEveryTarget) {
  ForEachTarget([&] {
    for (const FloatFormat& f : TinyFormats()) {
      std::vector<uint64_t> all;
      for (uint64_t v = 0; v < (uint64_t{1} << f.Width()); ++v) all.push_back(v);
      for (const fixed::Format& out : SmallFixed())
        for (const fixed::Policy& p : kPolicies) EXPECT_EQ(ToFixedMismatches(f, all, out, p), 0);
      for (const fixed::Format& in : SmallFixed()) {
        std::vector<int64_t> raw;
        for (int64_t v = 0; v < (int64_t{1} << in.Width()); ++v)
          raw.push_back(in.isSigned && v >= (int64_t{1} << (in.Width() - 1))
                            ? v - (int64_t{1} << in.Width())
                            : v);
        EXPECT_EQ(ToFloatMismatches(in, raw, f), 0);
      }
    }
  });
}

TEST(BitserialFloat, ConversionsBinary32EdgeBiased) {
  const FloatFormat f = FloatFormat::Binary32();
  std::mt19937_64 rng(13);
  std::vector<uint64_t> partner;
  std::vector<uint64_t> values = EdgeBiased(rng, 100000, &partner);
  // Values near the fixed formats' ranges and units: exponents 100..170.
  for (int i = 0; i < 20000; ++i) values[i] = (rng() & 0x807fffffu) | ((100 + rng() % 70) << 23);
  const fixed::Format outs[] = {fixed::Format::Signed(15, 16), fixed::Format::Signed(31, 0),
                                fixed::Format::Unsigned(8, 8)};
  for (const fixed::Format& out : outs)
    for (const fixed::Policy& p : kPolicies) EXPECT_EQ(ToFixedMismatches(f, values, out, p), 0);
  const std::vector<uint64_t> few(values.begin(), values.begin() + 8192);
  ForEachTarget([&] { EXPECT_EQ(ToFixedMismatches(f, few, outs[0], kPolicies[3]), 0); });
  // Fixed -> binary32: random s31.0 and s20.19 (and u40.0) values, some small.
  const fixed::Format ins[] = {fixed::Format::Signed(31, 0), fixed::Format::Signed(20, 19),
                               fixed::Format::Unsigned(40, 0)};
  for (const fixed::Format& in : ins) {
    std::vector<int64_t> raw(100000);
    for (auto& v : raw) {
      const int bits = 1 + static_cast<int>(rng() % in.Width());
      v = static_cast<int64_t>(rng() >> (64 - bits));
      if (in.isSigned && (rng() & 1) && bits < in.Width()) v = -v;
    }
    EXPECT_EQ(ToFloatMismatches(in, raw, f), 0) << in.Name();
    ForEachTarget([&] {
      EXPECT_EQ(ToFloatMismatches(in, std::vector<int64_t>(raw.begin(), raw.begin() + 4096), f), 0);
    });
  }
}

TEST(BitserialFloat, ConversionCyclesDoNotDependOnTheData) {
  const FloatFormat f = FloatFormat::Binary32();
  const fixed::Format fx = fixed::Format::Signed(15, 16);
  double toFixed = -1, toFloat = -1;
  for (uint64_t seed : {1, 2}) {
    Machine m(Profile("wavetracer"));
    std::mt19937_64 rng(seed);
    std::vector<uint64_t> v(m.VirtualPes());
    std::vector<int64_t> raw(m.VirtualPes());
    for (auto& x : v) x = rng() & f.Mask();
    for (auto& x : raw) x = static_cast<int64_t>(rng() >> 32) - (int64_t{1} << 31);
    MultiFloat a(m, f, "a");
    Multi b(m, fx, "b");
    a.Load(v), b.LoadRaw(raw);
    m.Report().Clear();
    ToFixed(a, fx, kPolicies[3]);
    ToFloat(b, f);
    const double c1 = m.Report().OpCycles("ftofixed"), c2 = m.Report().OpCycles("ffromfixed");
    if (toFixed < 0) toFixed = c1, toFloat = c2;
    EXPECT_EQ(c1, toFixed);
    EXPECT_EQ(c2, toFloat);
  }
  EXPECT_EQ(toFixed, FloatOpCycles(Profile("wavetracer"), "ftofixed", f, Space::kInternal, fx,
                                   kPolicies[3]));
  EXPECT_EQ(toFloat, FloatOpCycles(Profile("wavetracer"), "ffromfixed", f, Space::kInternal, fx));
}

TEST(BitserialFloat, ToFixedRefusesAFrameWiderThanTheMachineWord) {
  Machine m(Profile("wavetracer"));
  MultiFloat a(m, FloatFormat{11, 52, true}, "a");
  EXPECT_THROW(ToFixed(a, fixed::Format::Signed(100, 0)), zephyr::UserError);
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

// Closed forms of the float schedules (docs/float.md, "Cycle counts"), micro-op by
// micro-op, operands and result in internal memory.
std::map<std::string, int64_t> FloatMicroOps(const std::string& op, const FloatFormat& f) {
  Machine m(Profile("wavetracer"));
  MultiFloat a(m, f, "a"), b(m, f, "b");
  m.Report().Clear();
  if (op == "fcompare")
    Less(a, b);
  else if (op == "fmin")
    Min(a, b);
  else if (op == "fdiv")
    Div(a, b);
  else if (op == "fsqrt")
    Sqrt(a);
  return testutil::ChargedMicroOps(m, op);
}

TEST(BitserialFloat, CompareAndMinMaxClosedForms) {
  for (const FloatFormat& f : {FloatFormat{8, 23, true}, FloatFormat{5, 10, false},
                               FloatFormat{3, 2, true}, FloatFormat{11, 52, false}}) {
    const int64_t e = f.expBits, m = f.fracBits, w = f.Width();
    // Compare: both exponents scanned (hidden bit, all ones), one subtraction of the
    // magnitudes latching equality and "fraction not zero" along, then 30 flag operations
    // (16 of them reading a sign plane) and the result bit written.
    const std::map<std::string, int64_t> less = {{"readInternal", 4 * e + 2 * m + 6},
                                                 {"aluStep", 3 * e + m + 23},
                                                 {"flagOp", 30},
                                                 {"writeInternal", 1}};
    EXPECT_EQ(FloatMicroOps("fcompare", f), less) << f.Name();
    // Min: the same ordering, the pick, one selecting pass over both operands' w bits and
    // one masked pass writing the canonical NaN where both are NaN.
    const std::map<std::string, int64_t> min = {{"readInternal", 6 * e + 4 * m + 8},
                                                {"aluStep", 5 * e + 3 * m + 23},
                                                {"flagOp", 31},
                                                {"writeInternal", 2 * w}};
    EXPECT_EQ(FloatMicroOps("fmin", f), min) << f.Name();
  }
}

// The restoring loops dominate division and square root: per quotient bit (p + 2 of them,
// d = p) one subtraction over d+1 positions and a restore over d, so the counts grow as
// (p+2)·(2p+2) ALU steps, (p+2)·3p accumulator reads, (p+2)·(2p+1) accumulator writes and
// (p+2)·(p+1) memory reads (the divisor, the quotient bit as the mask); every other pass is
// linear in p for a flush-to-zero format. The second difference in p isolates the loop.
TEST(BitserialFloat, DivideAndSquareRootLoopsClosedForms) {
  auto second = [](const std::string& op, const std::string& micro) {
    int64_t c[3];
    for (int k = 0; k < 3; ++k) {
      auto counts = FloatMicroOps(op, FloatFormat{5, 6 + k, false});
      c[k] = counts[micro];
    }
    return c[2] - 2 * c[1] + c[0];
  };
  EXPECT_EQ(second("fdiv", "aluStep"), 4);
  EXPECT_EQ(second("fdiv", "accumulatorRead"), 6);
  EXPECT_EQ(second("fdiv", "accumulatorWrite"), 4);
  EXPECT_EQ(second("fdiv", "readInternal"), 2);
  // Square root: root bit j (from the top, j = 0 .. p+1) subtracts over j+3 positions and
  // restores j+2: 2j+6 ALU steps, 2j+5 accumulator writes, j+1 memory reads (the root bits
  // of the trial 4Y+1, and the new bit as the mask).
  EXPECT_EQ(second("fsqrt", "aluStep"), 2);
  EXPECT_EQ(second("fsqrt", "accumulatorWrite"), 2);
  EXPECT_EQ(second("fsqrt", "readInternal"), 1);
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

TEST(BitserialFloat, CyclesCommandKnowsEveryFloatOp) {
  // `zephyr cycles --op OP` prints the cycles FloatOpCycles counts, for every float op; the
  // conversions take the fixed side from --bits/--frac.
  for (const std::string& op : FloatOpNames()) {
    const char* args[] = {"zephyr", "cycles", "--op",   op.c_str(), "--float", "e5m10",
                          "--bits", "16",     "--frac", "4",        "--json"};
    testing::internal::CaptureStdout();
    EXPECT_EQ(RunZephyr(11, args), 0) << op;
    const nlohmann::json j = nlohmann::json::parse(testing::internal::GetCapturedStdout());
    const double want = FloatOpCycles(Profile("wavetracer"), op, FloatFormat{5, 10, true},
                                      Space::kInternal, fixed::Format::Signed(11, 4));
    EXPECT_GT(want, 0) << op;
    EXPECT_EQ(j["cycles"].get<double>(), want) << op;
  }
}

}  // namespace
}  // namespace zephyr::bitserial
