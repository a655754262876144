#include "fixed/reference.h"

#include <cmath>

#include "fixed/check.h"

namespace zephyr::fixed::reference {

namespace bmp = boost::multiprecision;

namespace {

Rational TwoTo(int k) {
  bmp::cpp_int p = 1;
  p <<= std::abs(k);
  return k >= 0 ? Rational(p) : Rational(bmp::cpp_int(1), p);
}

// The reference computes in unbounded cpp_int, then checks the result fits fixed/'s BigInt.
using Unbounded = bmp::cpp_int;

BigInt FloorOf(const Rational& x) {
  Unbounded n = bmp::numerator(x), d = bmp::denominator(x);  // d > 0
  Unbounded q = n / d;
  if (n < 0 && q * d != n) q -= 1;
  ZEPHYR_CHECK(bmp::msb(bmp::abs(q) + 1) < 500);
  return BigInt(q);
}

}  // namespace

Rational ExactValue(const Fixed& v) {
  return Rational(Unbounded(v.raw)) / TwoTo(v.format.fracBits);
}

Fixed FromExact(const Rational& x, Format out, Policy p, Status* status) {
  Rational scaled = x * TwoTo(out.fracBits);
  BigInt r = p.rounding == Rounding::kFloor ? FloorOf(scaled) : FloorOf(scaled + Rational(1, 2));
  // The range by definition: [-2^(w-1), 2^(w-1)) signed, [0, 2^w) unsigned.
  int w = out.Width();
  BigInt span = BigInt(1) << w;
  BigInt lo = out.isSigned ? BigInt(-(span / 2)) : BigInt(0);
  BigInt hi = lo + span - 1;
  if (r < lo || r > hi) {
    if (status) status->overflow = true;
    if (p.overflow == OverflowPolicy::kSaturate) {
      r = r < lo ? lo : hi;
    } else {
      // The representative of r modulo 2^w inside [lo, hi].
      r = lo + (((r - lo) % span) + span) % span;
    }
  }
  return Fixed{out, r};
}

Fixed Add(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  return FromExact(ExactValue(a) + ExactValue(b), out, p, s);
}
Fixed Sub(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  return FromExact(ExactValue(a) - ExactValue(b), out, p, s);
}
Fixed Neg(const Fixed& a, Format out, Policy p, Status* s) {
  return FromExact(-ExactValue(a), out, p, s);
}
Fixed Abs(const Fixed& a, Format out, Policy p, Status* s) {
  return FromExact(bmp::abs(ExactValue(a)), out, p, s);
}
int Compare(const Fixed& a, const Fixed& b) {
  Rational x = ExactValue(a), y = ExactValue(b);
  return x < y ? -1 : (x > y ? 1 : 0);
}
Fixed Min(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  return FromExact(std::min(ExactValue(a), ExactValue(b)), out, p, s);
}
Fixed Max(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  return FromExact(std::max(ExactValue(a), ExactValue(b)), out, p, s);
}
Fixed Mul(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  return FromExact(ExactValue(a) * ExactValue(b), out, p, s);
}
Fixed Div(const Fixed& a, const Fixed& b, Format out, Policy p, Status* s) {
  if (b.raw == 0) {
    if (s) s->divideByZero = true;
    BigInt span = BigInt(1) << out.Width();
    BigInt lo = out.isSigned ? BigInt(-(span / 2)) : BigInt(0);
    return Fixed{out, a.raw >= 0 ? BigInt(lo + span - 1) : lo};
  }
  return FromExact(ExactValue(a) / ExactValue(b), out, p, s);
}
Fixed Sqrt(const Fixed& a, Format out, Policy p, Status* s) {
  if (a.raw < 0) {
    if (s) s->invalid = true;
    return Fixed{out, 0};
  }
  // floor(sqrt(x) 2^fo) = isqrt(floor(x 2^(2 fo))), with Boost's integer square root.
  BigInt radicand = FloorOf(ExactValue(a) * TwoTo(2 * out.fracBits));
  Policy floor = p;
  floor.rounding = Rounding::kFloor;
  return FromExact(Rational(Unbounded(bmp::sqrt(radicand))) / TwoTo(out.fracBits), out, floor, s);
}
Fixed Shift(const Fixed& a, int k, Format out, Policy p, Status* s) {
  return FromExact(ExactValue(a) * TwoTo(k), out, p, s);
}
Fixed Convert(const Fixed& a, Format out, Policy p, Status* s) {
  return FromExact(ExactValue(a), out, p, s);
}
Fixed FromDouble(double x, Format out, Policy p, Status* s) {
  if (!std::isfinite(x)) {
    if (s) s->invalid = true;
    return Fixed{out, 0};
  }
  return FromExact(Rational(x), out, p, s);  // cpp_rational holds a double exactly
}
double ToDouble(const Fixed& v) {
  // A 128-bit float holds every value up to width 128 exactly; its conversion to double
  // rounds to nearest, ties to even.
  RefReal exact = RefReal(v.raw) / bmp::pow(RefReal(2), v.format.fracBits);
  return exact.convert_to<double>();
}

}  // namespace zephyr::fixed::reference
