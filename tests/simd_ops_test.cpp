// The primary pass's square root and division against fixed/ (bit-exact) on random data.
#include <gtest/gtest.h>

#include <random>

#include "bitserial/multi.h"
#include "hosts/simd_ops.h"

namespace zephyr::simd {
namespace {

using bitserial::Machine;
using bitserial::Multi;
using fixed::Fixed;
using fixed::Format;

std::vector<Fixed> Random(Format f, int n, std::mt19937_64& rng, bool nonNegative) {
  std::vector<Fixed> v;
  for (int i = 0; i < n; ++i) {
    fixed::BigInt raw = fixed::BigInt(rng() >> (64 - f.Width()));  // f.Width() <= 63
    if (!nonNegative && f.isSigned && (rng() & 1)) raw = -raw;
    if (raw > f.MaxRaw()) raw = f.MaxRaw();
    if (raw < f.MinRaw()) raw = f.MinRaw();
    if (i % 97 == 0) raw = 0;
    v.push_back({f, raw});
  }
  return v;
}

TEST(SimdOps, SqrtMatchesFixed) {
  std::mt19937_64 rng(1);
  Machine m(bitserial::Profile("wavetracer"), 8192 * 2);
  for (auto [fa, fo] : {std::pair{Format::Signed(9, 12), Format::Unsigned(5, 10)},
                        {Format::Unsigned(6, 20), Format::Unsigned(3, 14)},
                        {Format::Signed(12, 8), Format::Signed(7, 6)},
                        {Format::Unsigned(1, 5), Format::Unsigned(1, 9)}}) {
    auto a = Random(fa, 8192 * 2, rng, false);
    Multi ma(m, fa, "a");
    ma.Load(a);
    Multi r = SqrtFloor(ma, fo);
    for (size_t pe = 0; pe < a.size(); ++pe) {
      Fixed want = fixed::Sqrt(a[pe], fo);
      ASSERT_EQ(r.At(pe), want) << fixed::ToString(a[pe]) << " -> " << fo.Name();
    }
  }
  EXPECT_GT(m.Report().OpCycles("sqrt"), 0);
}

TEST(SimdOps, DivMatchesFixedForPositiveOperands) {
  std::mt19937_64 rng(2);
  Machine m(bitserial::Profile("wavetracer"));
  for (auto [fn, fd, fo] : {std::tuple{Format::Signed(8, 12), Format::Unsigned(4, 14), Format::Signed(9, 10)},
                            {Format::Unsigned(3, 20), Format::Signed(2, 6), Format::Unsigned(5, 8)},
                            {Format::Unsigned(10, 2), Format::Unsigned(2, 12), Format::Signed(6, 4)}}) {
    auto n = Random(fn, 8192, rng, true), d = Random(fd, 8192, rng, true);
    Multi mn(m, fn, "n"), md(m, fd, "d");
    mn.Load(n);
    md.Load(d);
    m.ClearFlags();
    Multi q = DivPositive(mn, md, fo);
    for (size_t pe = 0; pe < n.size(); ++pe) {
      fixed::Status st;
      Fixed want = fixed::Div(n[pe], d[pe], fo, {fixed::Rounding::Floor, fixed::OverflowPolicy::Saturate}, &st);
      ASSERT_EQ(q.At(pe), want) << fixed::ToString(n[pe]) << " / " << fixed::ToString(d[pe]);
      ASSERT_EQ(m.Overflow(pe), st.overflow || st.divideByZero) << pe;
    }
  }
}

}  // namespace
}  // namespace zephyr::simd
