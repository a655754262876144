// The kernels on many virtual-PE layers: at 384x384 (18 layers) the add kernel takes
// several vectors of PEs per strip and multiply, divide and square root run their whole
// schedule per vector from L1 buffers, paths a one-layer machine never reaches. Every op
// must still equal fixed/ (bits and flags) on every compiled Highway target; the reference
// is checked on a sample of PEs spread over every layer (the engine computes all of them).
#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <string>

#include "bitserial/multi.h"
#include "fixed/format.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;
using fixed::Policy;

using Ref = std::function<Fixed(const Fixed&, const Fixed&, fixed::Status*)>;

TEST(BitserialLayers, OpsOnEighteenLayersMatchFixedOnEveryTarget) {
  const Format fa = Format::Signed(9, 12), fb = Format::Signed(5, 10), fo = Format::Signed(11, 9);
  const Policy nearestSat{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  const Policy wrap{};
  const fixed::Fixed constant = fixed::FromDouble(-3.3125, Format::Signed(3, 6));
  testutil::ForEachTarget([&] {
    Machine m(Profile("wavetracer"), 384 * 384);
    ASSERT_EQ(m.Layers(), 18);
    std::mt19937_64 rng(7);
    std::vector<int64_t> ra(m.VirtualPes()), rb(m.VirtualPes());
    for (auto& x : ra) x = static_cast<int64_t>(rng()) >> (64 - fa.Width());
    for (auto& x : rb) x = static_cast<int64_t>(rng()) >> (64 - fb.Width());
    Multi a(m, fa, "a"), b(m, fb, "b");
    a.LoadRaw(ra);
    b.LoadRaw(rb);
    auto fixedA = [&](int64_t pe) { return Fixed{fa, ra[pe]}; };
    auto fixedB = [&](int64_t pe) { return Fixed{fb, rb[pe]}; };
    // Every PE flag (overflow, divide by zero, invalid) must match fixed/'s status; returns
    // how many sampled PEs raise overflow (so a test can require the case to occur).
    auto check = [&](const std::string& name, const std::function<Multi()>& op, const Ref& ref) {
      m.ClearFlags();
      const Multi r = op();
      int failures = 0, overflows = 0;
      for (int64_t pe = 0; pe < m.VirtualPes() && failures < 5; pe += 37) {
        fixed::Status st;
        const Fixed want = ref(fixedA(pe), fixedB(pe), &st);
        overflows += st.overflow;
        if (!(r.At(pe) == want) || m.Overflow(pe) != st.overflow ||
            m.DivideByZero(pe) != st.divideByZero || m.Invalid(pe) != st.invalid) {
          ++failures;
          ADD_FAILURE() << name << " at PE " << pe << " (layer " << pe / 8192 << "): got "
                        << fixed::ToString(r.At(pe)) << " flags " << m.Overflow(pe)
                        << m.DivideByZero(pe) << m.Invalid(pe) << ", want " << fixed::ToString(want)
                        << " flags " << st.overflow << st.divideByZero << st.invalid << " [target "
                        << m.Kernels().target << "]";
        }
      }
      return overflows;
    };
    check(
        "add", [&] { return Add(a, b, Format::Signed(9, 12)); },
        [&](auto& x, auto& y, auto* s) {
          return fixed::Add(x, y, Format::Signed(9, 12), wrap, s);
        });
    check(
        "sub", [&] { return Sub(a, b, fo, nearestSat); },
        [&](auto& x, auto& y, auto* s) { return fixed::Sub(x, y, fo, nearestSat, s); });
    check(
        "mul", [&] { return Mul(a, b, fo, nearestSat); },
        [&](auto& x, auto& y, auto* s) { return fixed::Mul(x, y, fo, nearestSat, s); });
    check(
        "square", [&] { return Square(a, fo, wrap); },
        [&](auto& x, auto&, auto* s) { return fixed::Mul(x, x, fo, wrap, s); });
    check(
        "mulUni", [&] { return Mul(a, Uni{constant}, fo, nearestSat); },
        [&](auto& x, auto&, auto* s) { return fixed::Mul(x, constant, fo, nearestSat, s); });
    // Division and square root into formats their results overflow on some PEs, under both
    // overflow policies (the flag, the saturated and the wrapped bits on every layer).
    const Format narrow = Format::Signed(2, 9);
    for (const Policy& p : {nearestSat, wrap}) {
      EXPECT_GT(check(
                    "div", [&] { return Div(a, b, fo, p); },
                    [&](auto& x, auto& y, auto* s) { return fixed::Div(x, y, fo, p, s); }),
                0);
      EXPECT_GT(check(
                    "sqrt", [&] { return Sqrt(a, narrow, p); },
                    [&](auto& x, auto&, auto* s) { return fixed::Sqrt(x, narrow, p, s); }),
                0);
    }
  });
}

}  // namespace
}  // namespace zephyr::bitserial
