// fixed/ against its exact reference: exhaustive for every format of width <= 8, random
// for widths 16..128, both overflow policies and both roundings.
#include "fixed/format.h"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <functional>
#include <mutex>
#include <random>
#include <thread>

#include "fixed/check.h"
#include "fixed/reference.h"

namespace zephyr::fixed {
namespace {

namespace ref = reference;

std::vector<Format> FormatsOfWidth(int w) {
  std::vector<Format> formats;
  for (int i = 0; i <= w - 1; ++i) formats.push_back(Format::Signed(i, w - 1 - i));
  for (int i = 0; i <= w; ++i) formats.push_back(Format::Unsigned(i, w - i));
  return formats;
}

std::vector<Format> FormatsUpToWidth(int maxWidth) {
  std::vector<Format> all;
  for (int w = 1; w <= maxWidth; ++w)
    for (Format f : FormatsOfWidth(w)) all.push_back(f);
  return all;
}

const Policy kPolicies[4] = {{Rounding::kFloor, OverflowPolicy::kWrap},
                             {Rounding::kFloor, OverflowPolicy::kSaturate},
                             {Rounding::kNearest, OverflowPolicy::kWrap},
                             {Rounding::kNearest, OverflowPolicy::kSaturate}};

std::string Describe(const Status& s) {
  return std::string(s.overflow ? "O" : "-") + (s.divideByZero ? "Z" : "-") +
         (s.invalid ? "I" : "-");
}

// The comparison every test uses: same value, same format, same flags.
::testing::AssertionResult SameResult(const std::string& what, const Fixed& got,
                                      const Status& gotStatus, const Fixed& want,
                                      const Status& wantStatus) {
  if (got == want && Describe(gotStatus) == Describe(wantStatus))
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << what << ": fixed/ gave " << ToString(got) << " flags " << Describe(gotStatus)
         << ", reference " << ToString(want) << " flags " << Describe(wantStatus);
}

using Binary = Fixed (*)(const Fixed&, const Fixed&, Format, Policy, Status*);
using Unary = Fixed (*)(const Fixed&, Format, Policy, Status*);
struct BinaryOp {
  const char* name;
  Binary impl;
  Binary reference;
};
struct UnaryOp {
  const char* name;
  Unary impl;
  Unary reference;
};

const BinaryOp kBinaryOps[] = {{"Add", Add, ref::Add}, {"Sub", Sub, ref::Sub},
                               {"Mul", Mul, ref::Mul}, {"Div", Div, ref::Div},
                               {"Min", Min, ref::Min}, {"Max", Max, ref::Max}};
const UnaryOp kUnaryOps[] = {{"Neg", Neg, ref::Neg},
                             {"Abs", Abs, ref::Abs},
                             {"Sqrt", Sqrt, ref::Sqrt},
                             {"Convert", Convert, ref::Convert}};

std::string Operands(const Fixed& a, const Fixed* b, Format out, Policy p) {
  std::string s = "(" + ToString(a);
  if (b) s += ", " + ToString(*b);
  return s + ") -> " + out.Name() + (p.rounding == Rounding::kFloor ? " floor" : " nearest") +
         (p.overflow == OverflowPolicy::kWrap ? " wrap" : " saturate");
}

// Collects failures from worker threads; reports at most a few.
class Failures {
 public:
  void Add(const ::testing::AssertionResult& r) {
    if (r) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (++count_ <= 8) messages_.push_back(r.message());
  }
  // One failure naming the count and the first few mismatches.
  void Report() const {
    if (count_ == 0) return;
    std::string all;
    for (auto& m : messages_) all += "\n  " + m;
    ADD_FAILURE() << count_ << " mismatches between fixed/ and the reference, first:" << all;
  }

 private:
  std::mutex mutex_;
  long count_ = 0;
  std::vector<std::string> messages_;
};

void ParallelFor(size_t n, const std::function<void(size_t)>& body) {
  unsigned threads = std::max(1u, std::min(4u, std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      for (size_t i = t; i < n; i += threads) body(i);
    });
  for (auto& th : pool) th.join();
}

void CheckBinary(const BinaryOp& op, const Fixed& a, const Fixed& b, Format out, Policy p,
                 Failures& failures) {
  Status s1, s2;
  Fixed got = op.impl(a, b, out, p, &s1);
  Fixed want = op.reference(a, b, out, p, &s2);
  failures.Add(SameResult(std::string(op.name) + Operands(a, &b, out, p), got, s1, want, s2));
}

void CheckUnary(const UnaryOp& op, const Fixed& a, Format out, Policy p, Failures& failures) {
  Status s1, s2;
  Fixed got = op.impl(a, out, p, &s1);
  Fixed want = op.reference(a, out, p, &s2);
  failures.Add(SameResult(std::string(op.name) + Operands(a, nullptr, out, p), got, s1, want, s2));
}

// ---- The test helpers themselves must be able to fail -----------------------------------
TEST(FixedTestHelpers, WrongReferenceValueFails) {
  Format f = Format::Signed(3, 4);
  Fixed a{f, 5}, b{f, 7};
  Status s;
  Fixed sum = Add(a, b, f, {}, &s);
  EXPECT_TRUE(SameResult("Add", sum, s, ref::Add(a, b, f, {}, nullptr), Status{}));
  Fixed wrong{f, sum.raw + 1};  // a deliberately wrong reference value
  EXPECT_FALSE(SameResult("Add", sum, s, wrong, Status{}));
  Status wrongFlags;
  wrongFlags.overflow = true;
  EXPECT_FALSE(SameResult("Add", sum, s, sum, wrongFlags));
  Failures failures;
  failures.Add(SameResult("Add", sum, s, wrong, Status{}));
  EXPECT_NONFATAL_FAILURE(failures.Report(), "mismatches between fixed/ and the reference");
}

// ---- Exhaustive: every format of total width <= 8, every operand pair -------------------
// Result formats and policies rotate over the pairs so that every format is also a result
// format, with every policy, and narrower results force overflow.
TEST(FixedExhaustive, BinaryOpsAllPairsWidthUpTo8) {
  std::vector<Format> formats = FormatsUpToWidth(8);
  std::vector<Format> outs = FormatsUpToWidth(8);
  Failures failures;
  ParallelFor(formats.size(), [&](size_t fi) {
    Format f = formats[fi];
    BigInt lo = f.MinRaw(), hi = f.MaxRaw();
    size_t k = fi;
    for (BigInt x = lo; x <= hi; ++x)
      for (BigInt y = lo; y <= hi; ++y, ++k) {
        Fixed a{f, x}, b{f, y};
        Policy p = kPolicies[k % 4];
        for (const BinaryOp& op : kBinaryOps) {
          CheckBinary(op, a, b, f, p, failures);  // the operands' own format
          if (k % 3 == 0)  // a third of the pairs also into a rotating other format
            CheckBinary(op, a, b, outs[(k * 7 + 3) % outs.size()], kPolicies[(k / 4) % 4],
                        failures);
        }
        EXPECT_EQ(Compare(a, b), ref::Compare(a, b));
      }
  });
  failures.Report();
}

TEST(FixedExhaustive, MixedFormatPairsWidthUpTo5) {
  std::vector<Format> formats = FormatsUpToWidth(5);
  Failures failures;
  ParallelFor(formats.size(), [&](size_t fi) {
    Format fa = formats[fi];
    size_t k = fi;
    for (Format fb : formats)
      for (BigInt x = fa.MinRaw(); x <= fa.MaxRaw(); ++x)
        for (BigInt y = fb.MinRaw(); y <= fb.MaxRaw(); ++y, ++k) {
          Fixed a{fa, x}, b{fb, y};
          Format out = formats[(k * 11) % formats.size()];
          for (const BinaryOp& op : kBinaryOps)
            CheckBinary(op, a, b, out, kPolicies[k % 4], failures);
          if (Compare(a, b) != ref::Compare(a, b))
            failures.Add(::testing::AssertionFailure() << "Compare" << Operands(a, &b, out, {}));
        }
  });
  failures.Report();
}

TEST(FixedExhaustive, UnaryOpsShiftsAndConversionsWidthUpTo8) {
  std::vector<Format> formats = FormatsUpToWidth(8);
  Failures failures;
  ParallelFor(formats.size(), [&](size_t fi) {
    Format f = formats[fi];
    for (BigInt x = f.MinRaw(); x <= f.MaxRaw(); ++x) {
      Fixed a{f, x};
      for (size_t oi = 0; oi < formats.size(); ++oi)
        for (Policy p : {kPolicies[(oi + fi) % 4], kPolicies[(oi + fi + 1) % 4]}) {
          Format out = formats[oi];
          for (const UnaryOp& op : kUnaryOps) CheckUnary(op, a, out, p, failures);
          for (int k : {-3, -1, 1, 2}) {
            Status s1, s2;
            failures.Add(SameResult("Shift " + std::to_string(k) + Operands(a, nullptr, out, p),
                                    Shift(a, k, out, p, &s1), s1, ref::Shift(a, k, out, p, &s2),
                                    s2));
          }
        }
      if (ToDouble(a) != ref::ToDouble(a))
        failures.Add(::testing::AssertionFailure() << "ToDouble " << ToString(a));
      // Round trip through double is exact for these widths.
      Status s;
      failures.Add(
          SameResult("FromDouble(ToDouble)", FromDouble(ToDouble(a), f, {}, &s), s, a, Status{}));
    }
  });
  failures.Report();
}

// ---- Random: >= 100,000 pairs per operation for widths 16, 32, 64, 96 and 128 ----------
// Operands are biased towards the edges of the range (where overflow and rounding live).
class Sampler {
 public:
  explicit Sampler(uint64_t seed) : rng_(seed) {}
  Format RandomFormat(int width) {
    bool isSigned = rng_() & 1;
    int magnitude = width - (isSigned ? 1 : 0);
    int intBits = static_cast<int>(rng_() % (magnitude + 1));
    return Format{isSigned, intBits, magnitude - intBits};
  }
  Fixed RandomValue(Format f) {
    int w = f.Width();
    BigInt bits = 0;
    for (int i = 0; i < w; i += 64) bits = (bits << 64) | BigInt(rng_());
    bits &= (BigInt(1) << w) - 1;
    switch (rng_() % 8) {
      case 0:
        bits >>= static_cast<int>(rng_() % w);
        break;  // small
      case 1:
        return Fixed{f, f.MaxRaw() - BigInt(rng_() % 4)};  // near max
      case 2:
        return Fixed{f, f.MinRaw() + BigInt(rng_() % 4)};  // near min
      case 3:
        return Fixed{f, BigInt(static_cast<int>(rng_() % 7) - 3) * (f.isSigned ? 1 : 0) +
                            (f.isSigned ? 0 : BigInt(rng_() % 4))};  // near zero
      default:
        break;
    }
    return Fixed::FromBits(f, bits);
  }
  Policy RandomPolicy() { return kPolicies[rng_() % 4]; }
  uint64_t Next() { return rng_(); }

 private:
  std::mt19937_64 rng_;
};

class FixedRandom : public ::testing::TestWithParam<int> {};

TEST_P(FixedRandom, EveryOperationAgainstReference) {
  const int width = GetParam();
  const int kPairs = 100000;
  Failures failures;
  ParallelFor(4, [&](size_t part) {
    Sampler sampler(1000 * width + part);
    for (int i = static_cast<int>(part); i < kPairs; i += 4) {
      Format fa = sampler.RandomFormat(width), fb = sampler.RandomFormat(width);
      // Results: the same width, or a narrower/wider one to provoke overflow and rounding.
      int outWidth =
          std::max(1, std::min(kMaxWidth, width + static_cast<int>(sampler.Next() % 17) - 8));
      Format out = sampler.RandomFormat(outWidth);
      Fixed a = sampler.RandomValue(fa), b = sampler.RandomValue(fb);
      Policy p = sampler.RandomPolicy();
      for (const BinaryOp& op : kBinaryOps) CheckBinary(op, a, b, out, p, failures);
      for (const UnaryOp& op : kUnaryOps) CheckUnary(op, a, out, p, failures);
      int k = static_cast<int>(sampler.Next() % 21) - 10;
      Status s1, s2;
      failures.Add(SameResult("Shift" + Operands(a, nullptr, out, p), Shift(a, k, out, p, &s1), s1,
                              ref::Shift(a, k, out, p, &s2), s2));
      if (Compare(a, b) != ref::Compare(a, b))
        failures.Add(::testing::AssertionFailure() << "Compare" << Operands(a, &b, out, p));
      if (ToDouble(a) != ref::ToDouble(a))
        failures.Add(::testing::AssertionFailure() << "ToDouble " << ToString(a));
    }
  });
  failures.Report();
}

INSTANTIATE_TEST_SUITE_P(Widths, FixedRandom, ::testing::Values(16, 32, 64, 96, 128));

// ---- Named cases: the rules stated in docs/fixed-point.md -------------------------------
TEST(FixedRules, RoundingAndOverflowExamples) {
  Format s34 = Format::Signed(3, 4);
  Format s30 = Format::Signed(3, 0);
  Status st;
  // -1.5 -> floor gives -2, nearest (half up) gives -1.
  Fixed m15 = FromDouble(-1.5, s34, {}, &st);
  EXPECT_EQ(Convert(m15, s30, {Rounding::kFloor}).raw, -2);
  EXPECT_EQ(Convert(m15, s30, {Rounding::kNearest}).raw, -1);
  EXPECT_EQ(Convert(FromDouble(2.5, s34), s30, {Rounding::kNearest}).raw, 3);
  // 7 + 1 overflows s3.0: wrap gives -8, saturate gives 7, both flag it.
  Fixed seven{s30, 7}, one{s30, 1};
  Status wrap, sat;
  EXPECT_EQ(Add(seven, one, s30, {Rounding::kFloor, OverflowPolicy::kWrap}, &wrap).raw, -8);
  EXPECT_EQ(Add(seven, one, s30, {Rounding::kFloor, OverflowPolicy::kSaturate}, &sat).raw, 7);
  EXPECT_TRUE(wrap.overflow);
  EXPECT_TRUE(sat.overflow);
  // Negating the most negative value overflows.
  Status neg;
  Neg(Fixed{s30, -8}, s30, {}, &neg);
  EXPECT_TRUE(neg.overflow);
  // Division by zero and the square root of a negative number are flagged.
  Status dz, inv;
  EXPECT_EQ(Div(seven, Fixed{s30, 0}, s30, {}, &dz).raw, 7);
  EXPECT_TRUE(dz.divideByZero);
  Sqrt(Fixed{s30, -1}, s30, {}, &inv);
  EXPECT_TRUE(inv.invalid);
  // sqrt(2) in u1.8, floored: 362/256 = 1.4140625.
  EXPECT_EQ(Sqrt(Fixed{Format::Unsigned(2, 0), 2}, Format::Unsigned(1, 8)).raw, 362);
  // NaN is invalid, not a silent zero.
  Status nan;
  FromDouble(std::nan(""), s34, {}, &nan);
  EXPECT_TRUE(nan.invalid);
}

TEST(FixedRules, BitsRoundTripTwosComplement) {
  Format f = Format::Signed(4, 3);
  Fixed v{f, -3};
  EXPECT_EQ(v.Bits(), BigInt(256 - 3));
  EXPECT_TRUE(v.Bit(7));
  EXPECT_FALSE(v.Bit(1));
  EXPECT_EQ(Fixed::FromBits(f, v.Bits()), v);
}

TEST(FixedRules, FormatNamesParseAndBadOnesAreUserErrors) {
  EXPECT_EQ(Format::Parse("s3.12"), Format::Signed(3, 12));
  EXPECT_EQ(Format::Parse("u8.0").Name(), "u8.0");
  EXPECT_THROW(Format::Parse("x3.1"), UserError);
  EXPECT_THROW(Format::Parse("s3"), UserError);
  EXPECT_THROW(Format::Parse("u0.0"), UserError);
  EXPECT_THROW(Format::Parse("s300.0"), UserError);
}

}  // namespace
}  // namespace zephyr::fixed
