// fixed/format.cpp — the fixed-point arithmetic, computed the way a shift-and-add datapath
// would: align by shifting, add/multiply integers, round by adding half an ulp before an
// arithmetic right shift, divide and take roots by the restoring (digit-by-digit) methods.
// fixed/reference.cpp computes the same results from exact rationals; tests compare them.
#include "fixed/format.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "fixed/check.h"

namespace zephyr::fixed {

namespace {

BigInt Pow2(int k) {
  ZEPHYR_CHECK_GE(k, 0);
  BigInt one = 1;
  return one << k;
}

// Arithmetic shift right (floor), which cpp_int's sign-magnitude >> does not promise.
BigInt FloorShiftRight(const BigInt& x, int k) {
  if (k <= 0) return x << -k;
  if (x >= 0) return x >> k;
  BigInt m = -x;
  return -((m + Pow2(k) - 1) >> k);
}

// Floor of n/d for any signs, d != 0.
BigInt FloorDiv(BigInt n, BigInt d) {
  if (d < 0) {
    n = -n;
    d = -d;
  }
  BigInt q = n / d;  // truncates toward zero
  if (n < 0 && q * d != n) q -= 1;
  return q;
}

// Restoring square root: one result bit per step, from the top, as a bit-serial PE does.
BigInt RestoringSqrt(const BigInt& x) {
  ZEPHYR_CHECK(x >= 0);
  if (x == 0) return 0;
  int bits = static_cast<int>(msb(x)) + 1;
  int top = (bits + 1) / 2;
  BigInt root = 0, remainder = 0;
  for (int i = top - 1; i >= 0; --i) {
    // Bring down the next two bits of x.
    BigInt pair = (x >> (2 * i)) & 3;
    remainder = (remainder << 2) | pair;
    BigInt trial = (root << 2) | 1;
    root <<= 1;
    if (remainder >= trial) {
      remainder -= trial;
      root |= 1;
    }
  }
  return root;
}

Fixed Fit(BigInt r, Format out, Policy p, Status* status) {
  BigInt lo = out.MinRaw(), hi = out.MaxRaw();
  if (r < lo || r > hi) {
    if (status) status->overflow = true;
    if (p.overflow == OverflowPolicy::kSaturate) {
      r = r < lo ? lo : hi;
    } else {
      BigInt modulus = Pow2(out.Width());
      r %= modulus;  // sign follows r
      if (r < 0) r += modulus;
      if (out.isSigned && r > hi) r -= modulus;
    }
  }
  return Fixed{out, r};
}

// The raw of `a` brought to `scale` fraction bits (scale >= a.format.fracBits: exact).
BigInt Aligned(const Fixed& a, int scale) { return a.raw << (scale - a.format.fracBits); }

}  // namespace

bool Format::IsValid() const {
  return intBits >= 0 && fracBits >= 0 && Width() >= 1 && Width() <= kMaxWidth;
}

BigInt Format::MinRaw() const { return isSigned ? BigInt(-Pow2(Width() - 1)) : BigInt(0); }
BigInt Format::MaxRaw() const {
  return isSigned ? BigInt(Pow2(Width() - 1) - 1) : BigInt(Pow2(Width()) - 1);
}

std::string Format::Name() const {
  return (isSigned ? "s" : "u") + std::to_string(intBits) + "." + std::to_string(fracBits);
}

Format Format::Parse(const std::string& text) {
  Format f;
  int i = 0, fr = 0;
  char sign = 0;
  int consumed = 0;
  if (std::sscanf(text.c_str(), "%c%d.%d%n", &sign, &i, &fr, &consumed) == 3 &&
      consumed == static_cast<int>(text.size()) && (sign == 's' || sign == 'u')) {
    f = Format{sign == 's', i, fr};
    if (f.IsValid()) return f;
  }
  throw UserError("bad fixed-point format '" + text + "': expected s<int>.<frac> or " +
                  "u<int>.<frac> with a total width of 1.." + std::to_string(kMaxWidth) +
                  " bits (e.g. s3.12)");
}

BigInt Fixed::Bits() const { return raw < 0 ? BigInt(raw + Pow2(format.Width())) : raw; }

Fixed Fixed::FromBits(Format format, const BigInt& bits) {
  ZEPHYR_CHECK(bits >= 0 && bits < Pow2(format.Width()));
  BigInt r = bits;
  if (format.isSigned && bit_test(bits, format.Width() - 1)) r -= Pow2(format.Width());
  return Fixed{format, r};
}

bool Fixed::Bit(int i) const { return bit_test(Bits(), i); }

std::string ToString(const Fixed& v) {
  char value[64];
  std::snprintf(value, sizeof value, "%.17g", ToDouble(v));
  return v.format.Name() + ":0x" + v.Bits().str(0, std::ios::hex) + " (" + value + ")";
}

Fixed RoundAndFit(const BigInt& num, int scale, Format out, Policy p, Status* status) {
  ZEPHYR_CHECK(out.IsValid());
  int drop = scale - out.fracBits;  // bits to remove (negative: to append)
  BigInt r;
  if (drop <= 0) {
    r = num << -drop;
  } else if (p.rounding == Rounding::kFloor) {
    r = FloorShiftRight(num, drop);
  } else {
    r = FloorShiftRight(num + Pow2(drop - 1), drop);  // add half an ulp, then shift
  }
  return Fit(std::move(r), out, p, status);
}

Fixed Add(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  int scale = std::max(a.format.fracBits, b.format.fracBits);
  return RoundAndFit(Aligned(a, scale) + Aligned(b, scale), scale, out, p, status);
}

Fixed Sub(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  int scale = std::max(a.format.fracBits, b.format.fracBits);
  return RoundAndFit(Aligned(a, scale) - Aligned(b, scale), scale, out, p, status);
}

Fixed Neg(const Fixed& a, Format out, Policy p, Status* status) {
  return RoundAndFit(-a.raw, a.format.fracBits, out, p, status);
}

Fixed Abs(const Fixed& a, Format out, Policy p, Status* status) {
  return RoundAndFit(a.raw < 0 ? BigInt(-a.raw) : a.raw, a.format.fracBits, out, p, status);
}

int Compare(const Fixed& a, const Fixed& b) {
  int scale = std::max(a.format.fracBits, b.format.fracBits);
  BigInt x = Aligned(a, scale), y = Aligned(b, scale);
  return x < y ? -1 : (x > y ? 1 : 0);
}

Fixed Min(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  return Convert(Compare(a, b) <= 0 ? a : b, out, p, status);
}

Fixed Max(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  return Convert(Compare(a, b) >= 0 ? a : b, out, p, status);
}

Fixed Mul(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  return RoundAndFit(a.raw * b.raw, a.format.fracBits + b.format.fracBits, out, p, status);
}

Fixed Div(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status) {
  ZEPHYR_CHECK(out.IsValid());
  if (b.raw == 0) {
    if (status) status->divideByZero = true;
    return Fixed{out, a.raw >= 0 ? out.MaxRaw() : out.MinRaw()};
  }
  // q = (a.raw / 2^fa) / (b.raw / 2^fb) in units of 2^-fo  =  a.raw 2^(fb+fo) / (b.raw 2^fa)
  BigInt n = a.raw << (b.format.fracBits + out.fracBits);
  BigInt d = b.raw << a.format.fracBits;
  if (d < 0) {
    n = -n;
    d = -d;
  }
  // Nearest: floor(n/d + 1/2) = floor((2n + d) / 2d), the restoring divider's extra bit.
  BigInt q = p.rounding == Rounding::kFloor ? FloorDiv(n, d) : FloorDiv(2 * n + d, 2 * d);
  return Fit(std::move(q), out, p, status);
}

Fixed Sqrt(const Fixed& a, Format out, Policy p, Status* status) {
  ZEPHYR_CHECK(out.IsValid());
  if (a.raw < 0) {
    if (status) status->invalid = true;
    return Fixed{out, 0};
  }
  // root in units of 2^-fo = floor(sqrt(a.raw 2^(2fo - fa))); flooring the radicand first
  // does not change the floor of its root.
  int k = 2 * out.fracBits - a.format.fracBits;
  BigInt radicand = k >= 0 ? BigInt(a.raw << k) : BigInt(a.raw >> -k);
  return Fit(RestoringSqrt(radicand), out, p, status);
}

Fixed Shift(const Fixed& a, int k, Format out, Policy p, Status* status) {
  return RoundAndFit(a.raw, a.format.fracBits - k, out, p, status);
}

Fixed Convert(const Fixed& a, Format out, Policy p, Status* status) {
  return RoundAndFit(a.raw, a.format.fracBits, out, p, status);
}

Fixed FromDouble(double x, Format out, Policy p, Status* status) {
  ZEPHYR_CHECK(out.IsValid());
  if (!std::isfinite(x)) {
    if (status) status->invalid = true;
    return Fixed{out, 0};
  }
  if (x == 0) return Fixed{out, 0};
  int exponent = 0;
  double mantissa = std::frexp(x, &exponent);  // x = mantissa 2^exponent, |mantissa| in [.5,1)
  auto m = static_cast<long long>(std::ldexp(mantissa, 53));  // exact: 53 significant bits
  // x = m 2^(exponent-53) = m 2^-scale
  return RoundAndFit(BigInt(m), 53 - exponent, out, p, status);
}

double ToDouble(const Fixed& v) {
  if (v.raw == 0) return 0.0;
  bool negative = v.raw < 0;
  BigInt magnitude = negative ? BigInt(-v.raw) : v.raw;
  int shift = static_cast<int>(msb(magnitude)) - 52;  // keep 53 significant bits
  BigInt m = magnitude;
  if (shift > 0) {
    m = magnitude >> shift;
    BigInt rest = magnitude - (m << shift);
    BigInt half = Pow2(shift - 1);
    if (rest > half || (rest == half && bit_test(m, 0))) m += 1;  // ties to even
  } else {
    shift = 0;
  }
  double d = std::ldexp(m.convert_to<double>(), shift - v.format.fracBits);
  return negative ? -d : d;
}

}  // namespace zephyr::fixed
