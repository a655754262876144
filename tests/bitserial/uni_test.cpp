// Uni operands in every binary operation and comparison (MultiC mixed uni and multi
// freely): the result and the per-PE flags equal those with the uni broadcast into a multi,
// and the uni's bits cost no PE memory read (bitserial/cost.h, Operand::uni).
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "tests/bitserial/closed_forms.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;
using fixed::Policy;
using testutil::ChargedMicroOps;
using testutil::ForEachTarget;
using testutil::kPolicies;

// An operation with the uni on the right (uniRight) or on the left, and the same with a
// broadcast multi in its place.
struct UniOp {
  const char* name;
  const char* charged;
  std::function<Multi(const Multi&, const Uni&, Format, Policy, bool uniRight)> withUni;
  std::function<Multi(const Multi&, const Multi&, Format, Policy)> withMulti;
};

template <typename F>
std::function<Multi(const Multi&, const Uni&, Format, Policy, bool)> Both(F f) {
  return [f](const Multi& a, const Uni& u, Format out, Policy p, bool right) {
    return right ? f(a, u, out, p) : f(u, a, out, p);
  };
}

const std::vector<UniOp>& Ops() {
  static const std::vector<UniOp> ops = {
      {"add", "add", Both([](auto& x, auto& y, Format o, Policy p) { return Add(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Add(x, y, o, p); }},
      {"sub", "sub", Both([](auto& x, auto& y, Format o, Policy p) { return Sub(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Sub(x, y, o, p); }},
      {"min", "min", Both([](auto& x, auto& y, Format o, Policy p) { return Min(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Min(x, y, o, p); }},
      {"max", "max", Both([](auto& x, auto& y, Format o, Policy p) { return Max(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Max(x, y, o, p); }},
      {"mul", "mulUni", Both([](auto& x, auto& y, Format o, Policy p) { return Mul(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Mul(x, y, o, p); }},
      {"div", "div", Both([](auto& x, auto& y, Format o, Policy p) { return Div(x, y, o, p); }),
       [](auto& x, auto& y, Format o, Policy p) { return Div(x, y, o, p); }},
      {"less", "compare", Both([](auto& x, auto& y, Format, Policy) { return Less(x, y); }),
       [](auto& x, auto& y, Format, Policy) { return Less(x, y); }},
      {"lessEqual", "compare",
       Both([](auto& x, auto& y, Format, Policy) { return LessEqual(x, y); }),
       [](auto& x, auto& y, Format, Policy) { return LessEqual(x, y); }},
      {"equal", "compare", Both([](auto& x, auto& y, Format, Policy) { return Equal(x, y); }),
       [](auto& x, auto& y, Format, Policy) { return Equal(x, y); }},
  };
  return ops;
}

TEST(BitserialUni, EveryBinaryOpAndComparisonEqualsTheBroadcastEveryTarget) {
  const Format fa = Format::Signed(2, 2), fu = Format::Signed(1, 1), out = Format::Signed(3, 2);
  ForEachTarget([&] {
    for (const UniOp& op : Ops())
      for (const Policy& p : kPolicies)
        for (bool right : {true, false})
          for (int bits = 0; bits < (1 << fu.Width()); ++bits) {
            const fixed::Fixed u = fixed::Fixed::FromBits(fu, bits);
            Machine m1(Profile("wavetracer"), 1 << fa.Width()),
                m2(Profile("wavetracer"), 1 << fa.Width());
            std::vector<fixed::Fixed> values;
            for (int v = 0; v < (1 << fa.Width()); ++v)
              values.push_back(fixed::Fixed::FromBits(fa, v));
            Multi a1(m1, fa, "a"), a2(m2, fa, "a");
            a1.Load(values), a2.Load(values);
            const Multi r1 = op.withUni(a1, Uni{u}, out, p, right);
            const Multi b2 = Broadcast(m2, u);
            const Multi r2 = right ? op.withMulti(a2, b2, out, p) : op.withMulti(b2, a2, out, p);
            for (int64_t pe = 0; pe < m1.VirtualPes(); ++pe) {
              ASSERT_EQ(r1.At(pe).raw, r2.At(pe).raw)
                  << op.name << " " << fixed::ToString(u) << " pe " << pe;
              ASSERT_EQ(m1.Overflow(pe), m2.Overflow(pe)) << op.name;
              ASSERT_EQ(m1.DivideByZero(pe), m2.DivideByZero(pe)) << op.name;
            }
          }
  });
}

std::map<std::string, int64_t> Counts(const UniOp& op, bool uni, int n) {
  Machine m(Profile("wavetracer"));
  const Format f = closed::Operand(n);
  Multi a(m, f, "a"), b(m, f, "b");
  const fixed::Fixed u = fixed::Fixed::FromBits(f, 0x5);
  m.Report().Clear();
  if (uni)
    op.withUni(a, Uni{u}, f, {}, true);
  else
    op.withMulti(a, b, f, {});
  return ChargedMicroOps(m, op.charged);
}

TEST(BitserialUni, TheUniCostsNoMemoryRead) {
  for (int n : {8, 16}) {
    for (const UniOp& op : Ops()) {
      if (std::string(op.name) == "mul") continue;  // mulUni: rows only for one bits
      auto multi = Counts(op, false, n), uni = Counts(op, true, n);
      EXPECT_LT(uni["readInternal"], multi["readInternal"]) << op.name;
      EXPECT_EQ(uni["aluStep"] > 0, true) << op.name;
    }
    // Closed forms: add and the comparisons read each of b's n bits once; min/max twice
    // (the comparison, then the select); everything else is unchanged.
    auto expectFewer = [&](const char* name, int64_t reads) {
      for (const UniOp& op : Ops())
        if (std::string(op.name) == name) {
          auto multi = Counts(op, false, n), uni = Counts(op, true, n);
          multi["readInternal"] -= reads;
          if (multi["readInternal"] == 0) multi.erase("readInternal");
          EXPECT_EQ(uni, multi) << name << " n=" << n;
        }
    };
    expectFewer("add", n);
    expectFewer("sub", n);
    expectFewer("less", n);
    expectFewer("equal", n);
    expectFewer("min", 2 * n);
    expectFewer("max", 2 * n);
    // Division by a uni: no pass for |b| (n reads, n ALU steps, n writes, a read and a
    // flag for its sign) nor for b == 0 (n reads, n ALU steps, a flag); the divisor bits of
    // every step come from the controller.
    for (const UniOp& op : Ops())
      if (std::string(op.name) == "div") {
        auto multi = Counts(op, false, n), uni = Counts(op, true, n);
        EXPECT_EQ(multi["aluStep"] - uni["aluStep"], 2 * n);
        EXPECT_EQ(multi["writeInternal"] - uni["writeInternal"], n);
        EXPECT_EQ(multi["flagOp"] - uni["flagOp"], 2);
      }
  }
}

// Floats: a uni float on either side of every binary operation and comparison gives the
// broadcast's bits, on every target, for every pair of a tiny format and on binary32.
TEST(BitserialUni, FloatOpsEqualTheBroadcastEveryTarget) {
  using fixed::FloatFormat;
  using FOp = std::function<std::vector<uint64_t>(const MultiFloat&, const MultiFloat&)>;
  using UOp = std::function<std::vector<uint64_t>(const MultiFloat&, const UniFloat&, bool)>;
  auto bits = [](const MultiFloat& r) {
    std::vector<uint64_t> v;
    for (int64_t pe = 0; pe < r.GetMachine().VirtualPes(); ++pe) v.push_back(r.At(pe));
    return v;
  };
  auto flag = [](const Multi& r) {
    std::vector<uint64_t> v;
    for (int64_t pe = 0; pe < r.GetMachine().VirtualPes(); ++pe) v.push_back(r.BitAt(0, pe));
    return v;
  };
  struct Case {
    const char* name;
    FOp multi;
    UOp uni;
  };
#define ZEPHYR_CASE(Op, Read)                                                                \
  Case {                                                                                     \
#Op, [&](const MultiFloat& a, const MultiFloat& b) { return Read(Op(a, b)); },             \
        [&](const MultiFloat& a, const UniFloat& u, bool right) {                               \
          return right ? Read(Op(a, u)) : Read(Op(u, a));                                       \
        } \
  }
  const std::vector<Case> cases = {
      ZEPHYR_CASE(Add, bits),  ZEPHYR_CASE(Sub, bits),       ZEPHYR_CASE(Mul, bits),
      ZEPHYR_CASE(Div, bits),  ZEPHYR_CASE(Min, bits),       ZEPHYR_CASE(Max, bits),
      ZEPHYR_CASE(Less, flag), ZEPHYR_CASE(LessEqual, flag), ZEPHYR_CASE(Equal, flag)};
#undef ZEPHYR_CASE
  auto check = [&](const FloatFormat& f, const std::vector<uint64_t>& values,
                   const std::vector<uint64_t>& unis) {
    for (const Case& c : cases)
      for (uint64_t u : unis)
        for (bool right : {true, false}) {
          Machine m(Profile("wavetracer"), static_cast<int64_t>(values.size()));
          MultiFloat a(m, f, "a");
          a.Load(values);
          const MultiFloat b = Broadcast(m, UniFloat{f, u});
          const auto want = right ? c.multi(a, b) : c.multi(b, a);
          EXPECT_EQ(c.uni(a, UniFloat{f, u}, right), want) << c.name << " " << f.Name() << " " << u;
        }
  };
  ForEachTarget([&] {
    const FloatFormat tiny{3, 2, true};
    std::vector<uint64_t> all;
    for (uint64_t v = 0; v < 64; ++v) all.push_back(v);
    check(tiny, all, all);
  });
  std::mt19937_64 rng(5);
  std::vector<uint64_t> values(4096);
  for (auto& v : values) v = rng() & 0xffffffffu;
  check(FloatFormat::Binary32(), values,
        {0x3f800000u, 0x80000000u, 0x7f800000u, 0x00000001u, 0xc2f6e979u});
}

TEST(BitserialUni, FloatUniReadsNoMemory) {
  const fixed::FloatFormat f = fixed::FloatFormat::Binary32();
  Machine m(Profile("wavetracer"));
  MultiFloat a(m, f, "a"), b(m, f, "b");
  m.Report().Clear();
  Add(a, b);
  const auto multi = ChargedMicroOps(m, "fadd");
  m.Report().Clear();
  Add(a, UniFloat{f, 0x3f800000u});
  const auto uni = ChargedMicroOps(m, "fadd");
  EXPECT_LT(uni.at("readInternal"), multi.at("readInternal"));
  EXPECT_EQ(uni.at("aluStep"), multi.at("aluStep"));
}

}  // namespace
}  // namespace zephyr::bitserial
