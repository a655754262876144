// Hardware-fidelity test 1: every bit-serial operation is bit-exact with fixed/ on every
// PE (result bits and the per-PE overflow flag), exhaustively for small widths, randomly
// for wide ones, under activity masks, and on every compiled Highway target.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <functional>
#include <random>

#include "bitserial/multi.h"
#include "fixed/format.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;
using fixed::Policy;
using namespace testutil;

Fixed RandomFixed(const Format& f, std::mt19937_64& rng) {
  fixed::BigInt bits = 0;
  for (int i = 0; i < f.Width(); i += 64) bits |= fixed::BigInt(rng()) << i;
  bits &= (fixed::BigInt(1) << f.Width()) - 1;
  return Fixed::FromBits(f, bits);
}

// All values of a format, or random ones, one per PE.
std::vector<Fixed> Values(const Format& f, int n, std::mt19937_64& rng) {
  std::vector<Fixed> v;
  for (int i = 0; i < n; ++i) v.push_back(RandomFixed(f, rng));
  return v;
}

using EngineBinary = std::function<Multi(const Multi&, const Multi&, Format, Policy)>;
using RefBinary = std::function<Fixed(const Fixed&, const Fixed&, Format, Policy, fixed::Status*)>;

// Runs op on a and b (one pair per PE) and compares every PE with the reference.
void CheckBinary(Machine& m, const char* name, const std::vector<Fixed>& a,
                 const std::vector<Fixed>& b, Format out, Policy p, const EngineBinary& op,
                 const RefBinary& ref) {
  Multi ma(m, a[0].format, "a"), mb(m, b[0].format, "b");
  ma.Load(a);
  mb.Load(b);
  m.ClearFlags();
  Multi r = op(ma, mb, out, p);
  int failures = 0;
  for (size_t pe = 0; pe < a.size() && failures < 5; ++pe) {
    fixed::Status st;
    Fixed want = ref(a[pe], b[pe], out, p, &st);
    Fixed got = r.At(pe);
    if (!(got == want) || st.overflow != m.Overflow(pe)) {
      ++failures;
      ADD_FAILURE() << name << " " << fixed::ToString(a[pe]) << ", " << fixed::ToString(b[pe])
                    << " -> " << out.Name() << " rounding " << int(p.rounding) << " overflow "
                    << int(p.overflow) << ": got " << fixed::ToString(got) << " ovf "
                    << m.Overflow(pe) << ", want " << fixed::ToString(want) << " ovf "
                    << st.overflow << " [target " << m.Kernels().target << "]";
    }
  }
}

struct BinaryOp {
  const char* name;
  EngineBinary engine;
  RefBinary ref;
};

std::vector<BinaryOp> BinaryOps() {
  return {
      {"add", [](auto& a, auto& b, Format o, Policy p) { return Add(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) {
         return fixed::Add(a, b, o, p, s);
       }},
      {"sub", [](auto& a, auto& b, Format o, Policy p) { return Sub(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) {
         return fixed::Sub(a, b, o, p, s);
       }},
      {"mul", [](auto& a, auto& b, Format o, Policy p) { return Mul(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) {
         return fixed::Mul(a, b, o, p, s);
       }},
      {"min", [](auto& a, auto& b, Format o, Policy p) { return Min(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) {
         return fixed::Min(a, b, o, p, s);
       }},
      {"max", [](auto& a, auto& b, Format o, Policy p) { return Max(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) {
         return fixed::Max(a, b, o, p, s);
       }},
  };
}

// Unary ops as binary ones that ignore b.
std::vector<BinaryOp> UnaryOps() {
  return {
      {"neg", [](auto& a, auto&, Format o, Policy p) { return Neg(a, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Neg(a, o, p, s); }},
      {"abs", [](auto& a, auto&, Format o, Policy p) { return Abs(a, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Abs(a, o, p, s); }},
      {"convert", [](auto& a, auto&, Format o, Policy p) { return Convert(a, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) {
         return fixed::Convert(a, o, p, s);
       }},
      {"shift+3", [](auto& a, auto&, Format o, Policy p) { return Shift(a, 3, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) {
         return fixed::Shift(a, 3, o, p, s);
       }},
      {"shift-2", [](auto& a, auto&, Format o, Policy p) { return Shift(a, -2, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) {
         return fixed::Shift(a, -2, o, p, s);
       }},
      {"square", [](auto& a, auto&, Format o, Policy p) { return Square(a, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) {
         return fixed::Mul(a, a, o, p, s);
       }},
  };
}

TEST(BitserialArith, ExhaustiveSmallWidthsEveryTarget) {
  ForEachTarget([] {
    Machine m(Profile("wavetracer"));
    const std::vector<Format> formats = SmallFormats();
    for (const Format& fa : formats)
      for (const Format& fb : formats) {
        std::vector<Fixed> a, b;
        AllPairs(fa, fb, a, b);
        for (const Format& out : {fa, Format::Signed(1, 2), Format::Unsigned(2, 4)})
          for (const Policy& p : kPolicies) {
            for (const BinaryOp& op : BinaryOps())
              CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
            if (&fb == &formats[0])
              for (const BinaryOp& op : UnaryOps())
                CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
          }
      }
  });
}

// Random data over all 8192 PEs for every width 1..64 and some wider ones. The best target
// runs every width; the others a sample (test 6 keeps each target honest on the same code).
TEST(BitserialArith, RandomWidthsAllPes) {
  std::mt19937_64 rng(7);
  Machine m(Profile("wavetracer"));
  std::vector<int> widths;
  for (int w = 1; w <= 64; ++w) widths.push_back(w);
  for (int w : {80, 100, 127}) widths.push_back(w);
  for (int w : widths) {
    const Format fa = Format::Signed(std::max(0, w - 1 - w / 3), std::min(w / 3, w - 1));
    const Format fb = w > 1 ? Format::Unsigned(w / 2, w - w / 2) : Format::Unsigned(1, 0);
    const Format out = fa;
    const Policy p = kPolicies[w % 4];
    auto a = Values(fa, 8192, rng), b = Values(fb, 8192, rng), c = Values(fa, 8192, rng);
    for (const BinaryOp& op : BinaryOps()) {
      if (w > 64 && std::string(op.name) == "mul") continue;  // product past 128 bits
      CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
      CheckBinary(m, op.name, a, c, out, p, op.engine, op.ref);
    }
    for (const BinaryOp& op : UnaryOps())
      if (w <= 64 || std::string(op.name) != "square")
        CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
  }
}

TEST(BitserialArith, OtherTargetsOnSampledWidths) {
  ForEachTarget([] {
    std::mt19937_64 rng(11);
    Machine m(Profile("wavetracer"));
    for (int w : {7, 31, 32, 33, 64}) {
      const Format f = Format::Signed(w / 2, w - 1 - w / 2);
      auto a = Values(f, 8192, rng), b = Values(f, 8192, rng);
      for (const Policy& p : kPolicies)
        for (const BinaryOp& op : BinaryOps())
          CheckBinary(m, op.name, a, b, f, p, op.engine, op.ref);
    }
  });
}

// Multiply by a uni constant equals fixed::Mul for constants with many and few one bits.
TEST(BitserialArith, MulUniMatchesFixed) {
  std::mt19937_64 rng(3);
  Machine m(Profile("wavetracer"));
  const Format fa = Format::Signed(7, 8), fc = Format::Signed(3, 4), out = Format::Signed(9, 6);
  auto a = Values(fa, 8192, rng);
  Multi ma(m, fa, "a");
  ma.Load(a);
  for (int64_t raw : {0, 1, -1, 5, -128, 127, 0x55, -0x2b}) {
    Fixed c{fc, raw};
    for (const Policy& p : kPolicies) {
      m.ClearFlags();
      Multi r = Mul(ma, Uni{c}, out, p);
      for (int pe = 0; pe < 8192; ++pe) {
        fixed::Status st;
        Fixed want = fixed::Mul(a[pe], c, out, p, &st);
        ASSERT_EQ(r.At(pe), want) << fixed::ToString(a[pe]) << " * " << fixed::ToString(c);
        ASSERT_EQ(m.Overflow(pe), st.overflow);
      }
    }
  }
}

// The engine adds a uni constant's non-adjacent form (runs of ones become +2^k - 2^j, a
// negative constant's top digit is subtracted), not its bits: every constant of a byte,
// signed and unsigned, and wide constants on both sides of the 62-bit form limit, still
// give fixed::Mul's bits and overflow flags.
TEST(BitserialArith, MulUniEveryConstantOfAByteAndWideOnes) {
  std::mt19937_64 rng(11);
  Machine m(Profile("wavetracer"));
  const Format fa = Format::Signed(6, 5);
  auto a = Values(fa, 8192, rng);
  Multi ma(m, fa, "a");
  ma.Load(a);
  const Policy p{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  auto check = [&](const Fixed& c, const Format& out) {
    m.ClearFlags();
    Multi r = Mul(ma, Uni{c}, out, p);
    for (int pe = 0; pe < 8192; pe += 61) {
      fixed::Status st;
      ASSERT_EQ(r.At(pe), fixed::Mul(a[pe], c, out, p, &st))
          << fixed::ToString(a[pe]) << " * " << fixed::ToString(c);
      ASSERT_EQ(m.Overflow(pe), st.overflow)
          << fixed::ToString(a[pe]) << " * " << fixed::ToString(c);
    }
  };
  for (const Format& fc : {Format::Signed(3, 4), Format::Unsigned(4, 4)})
    for (int64_t bits = 0; bits < 256; ++bits)
      ASSERT_NO_FATAL_FAILURE(check(Fixed::FromBits(fc, bits), Format::Signed(9, 6)));
  for (int width : {40, 61, 62, 63, 70})
    for (const Format& fc : {Format::Signed(width - 20, 20), Format::Unsigned(width - 20, 20)})
      for (int k = 0; k < 6; ++k) {
        // Random bits, then the extremes: all ones, the top bit alone, alternate bits.
        Fixed c = RandomFixed(fc, rng);
        const fixed::BigInt all = (fixed::BigInt(1) << width) - 1;
        if (k == 1) c = Fixed::FromBits(fc, all);
        if (k == 2) c = Fixed::FromBits(fc, fixed::BigInt(1) << (width - 1));
        if (k == 3) c = Fixed::FromBits(fc, all / 3);
        if (k == 4) c = Fixed::FromBits(fc, all - all / 3);
        ASSERT_NO_FATAL_FAILURE(check(c, Format::Signed(width - 10, 12)));
      }
}

TEST(BitserialArith, ComparisonsAndSelectMatchFixed) {
  std::mt19937_64 rng(5);
  Machine m(Profile("wavetracer"));
  const Format fa = Format::Signed(3, 4), fb = Format::Unsigned(2, 5);
  auto a = Values(fa, 8192, rng), b = Values(fb, 8192, rng);
  for (int pe = 0; pe < 8192; pe += 7) b[pe] = fixed::Convert(a[pe], fb);  // some ties
  Multi ma(m, fa, "a"), mb(m, fb, "b");
  ma.Load(a);
  mb.Load(b);
  Multi lt = ma<mb, le = ma <= mb, eq = ma == mb, gt = ma> mb;
  Multi sel = Select(lt, ma, mb, Format::Signed(2, 3),
                     {fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate});
  for (int pe = 0; pe < 8192; ++pe) {
    const int c = fixed::Compare(a[pe], b[pe]);
    ASSERT_EQ(lt.BitAt(0, pe), c < 0);
    ASSERT_EQ(le.BitAt(0, pe), c <= 0);
    ASSERT_EQ(eq.BitAt(0, pe), c == 0);
    ASSERT_EQ(gt.BitAt(0, pe), c > 0);
    Fixed want = fixed::Convert(c < 0 ? a[pe] : b[pe], Format::Signed(2, 3),
                                {fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate});
    ASSERT_EQ(sel.At(pe), want);
  }
}

// Under a random activity mask, assignment writes only active PEs (inactive PEs keep every
// bit), the overflow flag is set only where active, and elsewhere covers the rest.
TEST(BitserialArith, ActivityMaskKeepsInactivePes) {
  std::mt19937_64 rng(9);
  Machine m(Profile("wavetracer"));
  const Format f = Format::Signed(5, 2);
  auto a = Values(f, 8192, rng), b = Values(f, 8192, rng), t0 = Values(f, 8192, rng);
  std::vector<int64_t> maskRaw(8192);
  for (auto& x : maskRaw) x = rng() & 1;
  Multi ma(m, f, "a"), mb(m, f, "b"), t(m, f, "t"), mask(m, BoolFormat(), "mask");
  ma.Load(a), mb.Load(b), t.Load(t0), mask.LoadRaw(maskRaw);
  m.ClearFlags();
  Where(mask, [&] { t = Add(ma, mb, f); }).Elsewhere([&] { t = Mul(ma, mb, f); });
  for (int pe = 0; pe < 8192; ++pe) {
    fixed::Status st;
    Fixed want =
        maskRaw[pe] ? fixed::Add(a[pe], b[pe], f, {}, &st) : fixed::Mul(a[pe], b[pe], f, {}, &st);
    ASSERT_EQ(t.At(pe), want) << pe;
    ASSERT_EQ(m.Overflow(pe), st.overflow) << pe;
  }
  // A nested where with no else: the PEs outside keep their old value bit for bit.
  Multi u(m, f, "u");
  u.Load(t0);
  {
    WhereScope outer(mask);
    Multi pos = ma > mb;
    WhereScope inner(pos);
    u = Sub(ma, mb, f);
  }
  for (int pe = 0; pe < 8192; ++pe) {
    bool active = maskRaw[pe] && fixed::Compare(a[pe], b[pe]) > 0;
    ASSERT_EQ(u.At(pe), active ? fixed::Sub(a[pe], b[pe], f) : t0[pe]) << pe;
  }
}

// Host transfers round-trip raw integers and fixed values, and cost the host class.
// LoadRaw and ReadRaw move 64 PEs at a time through a bit-matrix transpose: every width up
// to 64 and past it, signed and unsigned, and a value list that ends inside a word, agree
// bit by bit with the planes (BitAt) and round-trip.
TEST(BitserialArith, HostTransfersEveryWidthAgreeWithThePlanes) {
  std::mt19937_64 rng(17);
  Machine m(Profile("wavetracer"));
  for (int width : {1, 2, 7, 31, 32, 33, 63, 64, 70})
    for (bool isSigned : {true, false}) {
      const Format f = isSigned ? Format::Signed(width - 1, 0) : Format::Unsigned(width, 0);
      std::vector<int64_t> raw(1000);  // 15 words and 40 PEs of the 16th; the rest stay 0
      for (auto& v : raw) {
        v = static_cast<int64_t>(rng());
        if (width < 64) {
          v &= (int64_t{1} << width) - 1;
          if (isSigned && (v >> (width - 1)) & 1) v -= int64_t{1} << width;
        }
      }
      Multi x(m, f, "x");
      x.LoadRaw(raw);
      for (int64_t pe = 0; pe < m.VirtualPes(); pe += pe < 1100 ? 1 : 97)
        for (int i = 0; i < width; ++i) {
          const uint64_t v = pe < 1000 ? static_cast<uint64_t>(raw[pe]) : 0;
          const bool want = i < 64 ? (v >> i) & 1 : (isSigned && (v >> 63));
          ASSERT_EQ(x.BitAt(i, pe), want)
              << "width " << width << " signed " << isSigned << " pe " << pe << " bit " << i;
        }
      if (width <= 64) {
        const std::vector<int64_t> back = x.ReadRaw();
        ASSERT_EQ(std::vector<int64_t>(back.begin(), back.begin() + 1000), raw)
            << "width " << width;
        for (int64_t pe = 1000; pe < m.VirtualPes(); ++pe) ASSERT_EQ(back[pe], 0) << pe;
      }
    }
}

TEST(BitserialArith, HostTransfersRoundTrip) {
  Machine m(Profile("wavetracer"), 384 * 384);
  const Format f = Format::Signed(20, 11);
  std::vector<int64_t> raw(m.VirtualPes());
  for (size_t i = 0; i < raw.size(); ++i)
    raw[i] = static_cast<int64_t>(i * 2654435761u % 4000000) - 2000000;
  Multi x(m, f, "x");
  x.LoadRaw(raw);
  EXPECT_EQ(x.ReadRaw(), raw);
  EXPECT_EQ(m.Report().ClassCycles(CycleClass::kHost),
            2 * 32 * 18 * m.Profile().Cost(MicroOp::kHostPlane));
}

}  // namespace
}  // namespace zephyr::bitserial
