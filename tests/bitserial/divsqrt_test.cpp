// Bit-serial division and square root: restoring algorithms built from the
// engine's kernels are bit-exact with fixed::Div / fixed::Sqrt on every PE — result bits
// and the per-PE overflow, divideByZero and invalid flags — exhaustively for widths <= 6,
// randomly over all 8192 PEs for widths 1..64 (and one wider), under activity masks, on
// every compiled Highway target; their cycle counts equal the closed forms of
// docs/bitserial.md at N and not N-1, whatever the data.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <functional>
#include <random>

#include "bitserial/multi.h"
#include "fixed/format.h"
#include "hosts/cmd/command.h"
#include "tests/bitserial/closed_forms.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;
using fixed::Policy;
using namespace testutil;

// What every PE must hold after the operation: the reference value and flags.
struct Expected {
  std::vector<Fixed> value;
  std::vector<fixed::Status> status;
};

Expected ExpectDiv(const std::vector<Fixed>& a, const std::vector<Fixed>& b, Format out, Policy p) {
  Expected e;
  for (size_t i = 0; i < a.size(); ++i) {
    fixed::Status st;
    e.value.push_back(fixed::Div(a[i], b[i], out, p, &st));
    e.status.push_back(st);
  }
  return e;
}

Expected ExpectSqrt(const std::vector<Fixed>& a, Format out, Policy p) {
  Expected e;
  for (const Fixed& x : a) {
    fixed::Status st;
    e.value.push_back(fixed::Sqrt(x, out, p, &st));
    e.status.push_back(st);
  }
  return e;
}

// Compares every PE (raw bits through ReadRaw for widths <= 64) with the expectation;
// reports at most a few failures.
void CheckPes(Machine& m, const Multi& r, const Expected& e, const std::string& what,
              const std::vector<Fixed>& a, const std::vector<Fixed>* b) {
  const bool narrow = r.Width() <= 64;
  const std::vector<int64_t> raw = narrow ? r.ReadRaw() : std::vector<int64_t>{};
  int failures = 0;
  for (size_t pe = 0; pe < e.value.size() && failures < 5; ++pe) {
    fixed::BigInt got = narrow ? fixed::BigInt(raw[pe]) : r.At(pe).raw;
    if (narrow && !r.Format().isSigned && got < 0) got += fixed::BigInt(1) << 64;  // u64
    const bool same = got == e.value[pe].raw;
    const fixed::Status& st = e.status[pe];
    if (same && m.Overflow(pe) == st.overflow && m.DivideByZero(pe) == st.divideByZero &&
        m.Invalid(pe) == st.invalid)
      continue;
    ++failures;
    ADD_FAILURE() << what << " PE " << pe << ": " << fixed::ToString(a[pe])
                  << (b ? " / " + fixed::ToString((*b)[pe]) : std::string(" sqrt")) << " -> got "
                  << fixed::ToString(r.At(pe)) << " flags " << m.Overflow(pe) << m.DivideByZero(pe)
                  << m.Invalid(pe) << ", want " << fixed::ToString(e.value[pe]) << " flags "
                  << st.overflow << st.divideByZero << st.invalid << " [target "
                  << m.Kernels().target << "]";
  }
}

std::string Tag(const char* op, Format a, Format b, Format out, Policy p) {
  return fmt::format("{} {} {} -> {} rounding {} overflow {}", op, a.Name(), b.Name(), out.Name(),
                     int(p.rounding), int(p.overflow));
}

// Every pair of values of every pair of small formats, into three result formats with all
// four policies; the references are computed once and every target must match them.
TEST(BitserialDivSqrt, ExhaustiveSmallWidthsEveryTarget) {
  struct Case {
    std::vector<Fixed> a, b;
    Format out;
    Policy p;
    Expected e;
    std::string tag;
  };
  std::vector<Case> divs, sqrts;
  const std::vector<Format> formats = SmallFormats();
  const std::vector<Format> outs = {Format::Signed(1, 2), Format::Unsigned(2, 4),
                                    Format::Signed(5, 0)};
  for (const Format& fa : formats)
    for (const Format& fb : formats) {
      std::vector<Fixed> a, b;
      AllPairs(fa, fb, a, b);
      for (const Format& out : {fa, outs[0], outs[1], outs[2]})
        for (const Policy& p : kPolicies)
          divs.push_back({a, b, out, p, ExpectDiv(a, b, out, p), Tag("div", fa, fb, out, p)});
    }
  for (const Format& fa : formats) {
    std::vector<Fixed> a;
    for (int i = 0; i < (1 << fa.Width()); ++i) a.push_back(Fixed::FromBits(fa, i));
    for (const Format& out : {fa, outs[0], outs[1], outs[2], Format::Unsigned(0, 3)})
      for (const Policy& p : kPolicies)
        sqrts.push_back({a, {}, out, p, ExpectSqrt(a, out, p), Tag("sqrt", fa, fa, out, p)});
  }
  ForEachTarget([&] {
    Machine m(Profile("wavetracer"));
    for (const Case& c : divs) {
      Multi ma(m, c.a[0].format, "a"), mb(m, c.b[0].format, "b");
      ma.Load(c.a), mb.Load(c.b);
      m.ClearFlags();
      CheckPes(m, Div(ma, mb, c.out, c.p), c.e, c.tag, c.a, &c.b);
    }
    for (const Case& c : sqrts) {
      Multi ma(m, c.a[0].format, "a");
      ma.Load(c.a);
      m.ClearFlags();
      CheckPes(m, Sqrt(ma, c.out, c.p), c.e, c.tag, c.a, nullptr);
    }
  });
}

// Random values biased toward zero and the ends of the range (every kind of special case:
// b == 0, the most negative dividend, negative radicands).
std::vector<Fixed> Values(const Format& f, int n, std::mt19937_64& rng) {
  std::vector<Fixed> v;
  for (int i = 0; i < n; ++i) {
    fixed::BigInt bits = 0;
    for (int k = 0; k < f.Width(); k += 64) bits |= fixed::BigInt(rng()) << k;
    bits &= (fixed::BigInt(1) << f.Width()) - 1;
    Fixed x = Fixed::FromBits(f, bits);
    switch (rng() % 16) {
      case 0:
        x.raw = 0;
        break;
      case 1:
        x.raw = f.MinRaw();
        break;
      case 2:
        x.raw = f.MaxRaw();
        break;
      case 3:
        x.raw = x.raw >> (rng() % f.Width());
        break;  // small magnitudes
      default:
        break;
    }
    v.push_back(x);
  }
  return v;
}

void RandomRun(Machine& m, int w, std::mt19937_64& rng, bool allPolicies) {
  const Format fa = Format::Signed(std::max(0, w - 1 - w / 3), std::min(w / 3, w - 1));
  const Format fu = w > 1 ? Format::Unsigned(w / 2, w - w / 2) : Format::Unsigned(1, 0);
  const Format fs = Format::Signed(w - 1 - (w - 1) / 2, (w - 1) / 2);
  const auto a = Values(fa, 8192, rng), u = Values(fu, 8192, rng), s = Values(fs, 8192, rng);
  Multi ma(m, fa, "a"), mu(m, fu, "u"), ms(m, fs, "s");
  ma.Load(a), mu.Load(u), ms.Load(s);
  auto div = [&](const Multi& x, const std::vector<Fixed>& xv, const Multi& y,
                 const std::vector<Fixed>& yv, Format out, Policy p) {
    m.ClearFlags();
    CheckPes(m, Div(x, y, out, p), ExpectDiv(xv, yv, out, p),
             Tag("div", x.Format(), y.Format(), out, p), xv, &yv);
  };
  auto sqrt = [&](const Multi& x, const std::vector<Fixed>& xv, Format out, Policy p) {
    m.ClearFlags();
    CheckPes(m, Sqrt(x, out, p), ExpectSqrt(xv, out, p),
             Tag("sqrt", x.Format(), x.Format(), out, p), xv, nullptr);
  };
  for (int k = 0; k < 4; ++k) {
    if (!allPolicies && k != w % 4) continue;
    const Policy p = kPolicies[k];
    div(ma, a, ms, s, fa, p);  // signed / signed
    div(mu, u, ma, a, fs, p);  // unsigned / signed into another format
    div(ma, a, mu, u, fu, p);  // signed / unsigned into an unsigned format
    sqrt(ma, a, fa, p);
    sqrt(mu, u, fs, p);
  }
}

// Every width 1..64 and one wider on the best target, all 8192 PEs.
TEST(BitserialDivSqrt, RandomWidthsAllPes) {
  std::mt19937_64 rng(17);
  Machine m(Profile("wavetracer"));
  for (int w = 1; w <= 64; ++w) RandomRun(m, w, rng, false);
  RandomRun(m, 100, rng, false);
}

TEST(BitserialDivSqrt, RandomSampledWidthsEveryTarget) {
  ForEachTarget([] {
    std::mt19937_64 rng(23);
    Machine m(Profile("wavetracer"));
    for (int w : {7, 33, 64}) RandomRun(m, w, rng, true);
  });
}

// Under a random mask: inactive PEs keep every bit of the destination and raise no flag;
// elsewhere covers the rest.
TEST(BitserialDivSqrt, ActivityMaskKeepsInactivePes) {
  std::mt19937_64 rng(29);
  Machine m(Profile("wavetracer"));
  const Format f = Format::Signed(6, 5);
  const Policy sat{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  auto a = Values(f, 8192, rng), b = Values(f, 8192, rng), t0 = Values(f, 8192, rng);
  std::vector<int64_t> maskRaw(8192);
  for (auto& x : maskRaw) x = rng() & 1;
  Multi ma(m, f, "a"), mb(m, f, "b"), t(m, f, "t"), u(m, f, "u"), mask(m, BoolFormat(), "mask");
  ma.Load(a), mb.Load(b), t.Load(t0), u.Load(t0), mask.LoadRaw(maskRaw);
  m.ClearFlags();
  Where(mask, [&] { t = Div(ma, mb, f, sat); }).Elsewhere([&] { t = Sqrt(ma, f, sat); });
  for (int pe = 0; pe < 8192; ++pe) {
    fixed::Status st;
    Fixed want =
        maskRaw[pe] ? fixed::Div(a[pe], b[pe], f, sat, &st) : fixed::Sqrt(a[pe], f, sat, &st);
    ASSERT_EQ(t.At(pe), want) << pe;
    ASSERT_EQ(m.Overflow(pe), st.overflow) << pe;
    ASSERT_EQ(m.DivideByZero(pe), st.divideByZero) << pe;
    ASSERT_EQ(m.Invalid(pe), st.invalid) << pe;
  }
  // Only under the mask: the others keep their old bits and no flag.
  m.ClearFlags();
  {
    WhereScope scope(mask);
    u = Div(ma, mb, f);
    u = Sqrt(u, f);
  }
  for (int pe = 0; pe < 8192; ++pe) {
    fixed::Status st;
    Fixed want = t0[pe];
    if (maskRaw[pe]) want = fixed::Sqrt(fixed::Div(a[pe], b[pe], f, {}, &st), f, {}, &st);
    ASSERT_EQ(u.At(pe), want) << pe;
    ASSERT_EQ(m.Overflow(pe), st.overflow) << pe;
    ASSERT_EQ(m.DivideByZero(pe), st.divideByZero) << pe;
    ASSERT_EQ(m.Invalid(pe), st.invalid) << pe;
  }
}

// ---- cycles ------------------------------------------------------------------------------

// n-bit signed integers, result in the operands' format, Floor/Wrap (docs/bitserial.md).
TEST(BitserialDivSqrt, ClosedFormCycles) {
  for (int n = 1; n <= 64; ++n) {
    const Format f = Format::Signed(n - 1, 0);
    const int h = n / 2;  // root bits
    const std::string tag = " n=" + std::to_string(n);
    auto div = [&](auto& a, auto& b) { return Div(a, b, f); };
    auto sqrt = [&](auto& a, auto&) { return Sqrt(a, f); };
    ExpectFormula(Cycles("wavetracer", f, f, "div", div), 6 * n * n + 22 * n + 16,
                  "wavetracer div" + tag);
    ExpectFormula(Cycles("wavetracer", f, f, "sqrt", sqrt), 3 * h * h + 11 * h + 4 * n + 1,
                  "wavetracer sqrt" + tag);
    if (n <= 40) {
      ExpectFormula(Cycles("mpp", f, f, "div", div), n * n + 14 * n + 13, "mpp div" + tag);
      ExpectFormula(Cycles("mpp", f, f, "sqrt", sqrt), h * (h - 1) / 2 + 4 * h + 3 * n + 2,
                    "mpp sqrt" + tag);
    }
  }
}

// Whatever the operands hold (zero divisors, negative radicands, the extremes, random), div
// and sqrt charge exactly their closed forms' micro-ops (tests/bitserial/closed_forms.h, an
// independent count), and on 18 layers 18 times as many.
TEST(BitserialDivSqrt, CyclesDoNotDependOnDataAndScaleWithLayers) {
  const int n = 16;
  const Format f = Format::Signed(n - 1, 0);
  const Policy p{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  const Space I = Space::kInternal;
  std::mt19937_64 rng(31);
  for (int data = 0; data < 4; ++data) {
    Machine m(Profile("wavetracer"));
    const auto a = Values(f, 8192, rng), b = Values(f, 8192, rng);
    std::vector<Fixed> va = a, vb = b;
    if (data < 3) {
      const fixed::BigInt fill[] = {0, f.MinRaw(), f.MaxRaw()};
      for (auto& x : vb) x.raw = fill[data];  // all zero, all most negative, all max
      for (auto& x : va) x.raw = fill[(data + 1) % 3];
    }
    Multi ma(m, f, "a"), mb(m, f, "b");
    ma.Load(va), mb.Load(vb);
    Multi q = Div(ma, mb, f, p);
    Multi r = Sqrt(ma, Format::Signed(n / 2 - 2, 0), p);
    EXPECT_EQ(ChargedMicroOps(m, "div"), closed::Div(n, p, I, I, I).n) << "data " << data;
    EXPECT_EQ(ChargedMicroOps(m, "sqrt"), closed::Sqrt(n, n / 2 - 1, p, I, I).n) << "data " << data;
  }
  Machine m(Profile("wavetracer"), 384 * 384);
  Multi a(m, f, "a"), b(m, f, "b");
  Multi q = Div(a, b, f, p);
  closed::Counts want = closed::Div(n, p, I, I, I);
  for (auto& [op, k] : want.n) k *= 18;
  EXPECT_EQ(ChargedMicroOps(m, "div"), want.n);
}

TEST(BitserialDivSqrt, CyclesCommandPrintsTheClosedForms) {
  const char* div[] = {"zephyr", "cycles", "--profile", "mpp", "--op", "div", "--bits", "8"};
  testing::internal::CaptureStdout();
  EXPECT_EQ(RunZephyr(8, div), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find(": 189 cycles per layer"),
            std::string::npos);
  const char* sqrt[] = {"zephyr", "cycles", "--op", "sqrt", "--bits", "16", "--json"};
  testing::internal::CaptureStdout();
  EXPECT_EQ(RunZephyr(7, sqrt), 0);
  // WaveTracer, n = 16, h = 8: 3·64 + 88 + 64 + 1.
  EXPECT_NE(testing::internal::GetCapturedStdout().find("\"cycles\": 345.0"), std::string::npos);
}

}  // namespace
}  // namespace zephyr::bitserial
