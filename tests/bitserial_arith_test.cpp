// Hardware-fidelity test 1: every bit-serial operation is bit-exact with fixed/ on every
// PE (result bits and the per-PE overflow flag), exhaustively for small widths, randomly
// for wide ones, under activity masks, and on every compiled Highway target.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <functional>
#include <random>

#include "bitserial/multi.h"
#include "fixed/format.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;
using fixed::Policy;

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

const Policy kPolicies[] = {{fixed::Rounding::Floor, fixed::OverflowPolicy::Wrap},
                            {fixed::Rounding::Nearest, fixed::OverflowPolicy::Wrap},
                            {fixed::Rounding::Floor, fixed::OverflowPolicy::Saturate},
                            {fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate}};

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
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) { return fixed::Add(a, b, o, p, s); }},
      {"sub", [](auto& a, auto& b, Format o, Policy p) { return Sub(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) { return fixed::Sub(a, b, o, p, s); }},
      {"mul", [](auto& a, auto& b, Format o, Policy p) { return Mul(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) { return fixed::Mul(a, b, o, p, s); }},
      {"min", [](auto& a, auto& b, Format o, Policy p) { return Min(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) { return fixed::Min(a, b, o, p, s); }},
      {"max", [](auto& a, auto& b, Format o, Policy p) { return Max(a, b, o, p); },
       [](auto& a, auto& b, Format o, Policy p, fixed::Status* s) { return fixed::Max(a, b, o, p, s); }},
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
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Convert(a, o, p, s); }},
      {"shift+3", [](auto& a, auto&, Format o, Policy p) { return Shift(a, 3, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Shift(a, 3, o, p, s); }},
      {"shift-2", [](auto& a, auto&, Format o, Policy p) { return Shift(a, -2, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Shift(a, -2, o, p, s); }},
      {"square", [](auto& a, auto&, Format o, Policy p) { return Square(a, o, p); },
       [](auto& a, auto&, Format o, Policy p, fixed::Status* s) { return fixed::Mul(a, a, o, p, s); }},
  };
}

// Formats of width <= 6, signed and unsigned, with different splits.
std::vector<Format> SmallFormats() {
  return {Format::Signed(2, 3), Format::Unsigned(3, 3), Format::Signed(0, 2), Format::Unsigned(1, 0),
          Format::Signed(4, 0), Format::Unsigned(0, 5)};
}

// Runs `body` once per compiled Highway target (hwy's own test pattern).
void ForEachTarget(const std::function<void()>& body) {
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    body();
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(BitserialArith, ExhaustiveSmallWidthsEveryTarget) {
  ForEachTarget([] {
    Machine m(Profile("wavetracer"));
    const std::vector<Format> formats = SmallFormats();
    for (const Format& fa : formats)
      for (const Format& fb : formats) {
        // Every pair of values: fa has 2^wa values, fb 2^wb; at most 4096 pairs.
        std::vector<Fixed> a, b;
        for (int i = 0; i < (1 << fa.Width()); ++i)
          for (int j = 0; j < (1 << fb.Width()); ++j) {
            a.push_back(Fixed::FromBits(fa, i));
            b.push_back(Fixed::FromBits(fb, j));
          }
        for (const Format& out : {fa, Format::Signed(1, 2), Format::Unsigned(2, 4)})
          for (const Policy& p : kPolicies) {
            for (const BinaryOp& op : BinaryOps()) CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
            if (&fb == &formats[0])
              for (const BinaryOp& op : UnaryOps()) CheckBinary(m, op.name, a, b, out, p, op.engine, op.ref);
          }
      }
  });
}

}  // namespace
}  // namespace zephyr::bitserial
