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
  const Policy nearestSat{fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate};
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
    auto check = [&](const std::string& name, const std::function<Multi()>& op, const Ref& ref,
                     bool (Machine::*flag)(int64_t) const) {
      m.ClearFlags();
      const Multi r = op();
      int failures = 0;
      for (int64_t pe = 0; pe < m.VirtualPes() && failures < 5; pe += 37) {
        fixed::Status st;
        const Fixed want = ref(fixedA(pe), fixedB(pe), &st);
        const bool wantFlag = name == "div" ? st.divideByZero : name == "sqrt" ? st.invalid : st.overflow;
        if (!(r.At(pe) == want) || (m.*flag)(pe) != wantFlag) {
          ++failures;
          ADD_FAILURE() << name << " at PE " << pe << " (layer " << pe / 8192 << "): got "
                        << fixed::ToString(r.At(pe)) << ", want " << fixed::ToString(want)
                        << " [target " << m.Kernels().target << "]";
        }
      }
    };
    check("add", [&] { return Add(a, b, Format::Signed(9, 12)); },
          [&](auto& x, auto& y, auto* s) { return fixed::Add(x, y, Format::Signed(9, 12), wrap, s); },
          &Machine::Overflow);
    check("sub", [&] { return Sub(a, b, fo, nearestSat); },
          [&](auto& x, auto& y, auto* s) { return fixed::Sub(x, y, fo, nearestSat, s); },
          &Machine::Overflow);
    check("mul", [&] { return Mul(a, b, fo, nearestSat); },
          [&](auto& x, auto& y, auto* s) { return fixed::Mul(x, y, fo, nearestSat, s); },
          &Machine::Overflow);
    check("square", [&] { return Square(a, fo, wrap); },
          [&](auto& x, auto&, auto* s) { return fixed::Mul(x, x, fo, wrap, s); }, &Machine::Overflow);
    check("mulUni", [&] { return Mul(a, Uni{constant}, fo, nearestSat); },
          [&](auto& x, auto&, auto* s) { return fixed::Mul(x, constant, fo, nearestSat, s); },
          &Machine::Overflow);
    check("div", [&] { return Div(a, b, fo, nearestSat); },
          [&](auto& x, auto& y, auto* s) { return fixed::Div(x, y, fo, nearestSat, s); },
          &Machine::DivideByZero);
    check("sqrt", [&] { return Sqrt(a, fo, wrap); },
          [&](auto& x, auto&, auto* s) { return fixed::Sqrt(x, fo, wrap, s); }, &Machine::Invalid);
  });
}

}  // namespace
}  // namespace zephyr::bitserial
