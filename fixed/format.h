// fixed/format.h — scalar fixed-point formats and their arithmetic.
//
// This file defines the arithmetic that the bit-serial array (bitserial/) must reproduce
// bit for bit. The rule behind every operation is the same:
//
//   1. compute the exact mathematical result from the operands' exact values;
//   2. round it to the result format's fraction bits with the named Rounding;
//   3. fit it into the result format's range with the named OverflowPolicy, raising the
//      Status flag `overflow` whenever the rounded exact result is outside the range.
//
// Operands and the result may all have different formats. docs/fixed-point.md states the
// rules in full; fixed/reference.h computes the same results a second, independent way
// (Boost.Multiprecision rationals) and the tests compare the two.
#pragma once

#include <boost/multiprecision/cpp_int.hpp>
#include <cstdint>
#include <string>

namespace zephyr::fixed {

// The widest format we support is 128 bits. Raw values and every temporary (a 256-bit
// product, a 384-bit shifted dividend) fit a fixed 512-bit integer, which needs no heap;
// ZEPHYR_CHECKs guard the bound.
inline constexpr int kMaxWidth = 128;
using BigInt = boost::multiprecision::number<boost::multiprecision::cpp_int_backend<
    512, 512, boost::multiprecision::signed_magnitude, boost::multiprecision::unchecked, void>>;

// A format: signedness, integer bits, fraction bits. Value = raw × 2^-fracBits, where raw
// is a two's-complement integer of Width() bits (signed) or a plain unsigned integer.
// The sign bit is not counted in intBits:  s3.4 is 1+3+4 = 8 bits, range [-8, 8-1/16].
struct Format {
  bool isSigned = true;
  int intBits = 0;
  int fracBits = 0;

  static Format Signed(int intBits, int fracBits) { return {true, intBits, fracBits}; }
  static Format Unsigned(int intBits, int fracBits) { return {false, intBits, fracBits}; }

  int Width() const { return (isSigned ? 1 : 0) + intBits + fracBits; }
  bool IsValid() const;      // 1 <= Width() <= kMaxWidth, intBits >= 0, fracBits >= 0
  BigInt MinRaw() const;     // -2^(w-1) or 0
  BigInt MaxRaw() const;     // 2^(w-1)-1 or 2^w-1
  std::string Name() const;  // "s3.4", "u8.0"
  // Parses Name()'s form; throws UserError naming the text on failure.
  static Format Parse(const std::string& text);

  friend bool operator==(const Format&, const Format&) = default;
};

// Step 2 of the rule. Floor is what a shift-based datapath does (truncate toward -inf);
// Nearest rounds half-way cases up (toward +inf): floor(x + 1/2 ulp), one add before the
// shift in hardware.
enum class Rounding { kFloor, kNearest };
// Step 3 of the rule. Wrap keeps the low Width() bits (two's complement); Saturate clamps
// to the nearest end of the range.
enum class OverflowPolicy { kWrap, kSaturate };

struct Policy {
  Rounding rounding = Rounding::kFloor;
  OverflowPolicy overflow = OverflowPolicy::kWrap;
};

// Sticky flags: operations only ever set them.
struct Status {
  bool overflow = false;      // the rounded exact result did not fit the result format
  bool divideByZero = false;  // Div with a zero divisor
  bool invalid = false;       // Sqrt of a negative value; FromDouble of NaN/inf
  bool Any() const { return overflow || divideByZero || invalid; }
  Status& operator|=(const Status& o) {
    overflow |= o.overflow;
    divideByZero |= o.divideByZero;
    invalid |= o.invalid;
    return *this;
  }
};

// A value: its format and its raw integer (within [MinRaw, MaxRaw]).
struct Fixed {
  Format format;
  BigInt raw;

  // The raw value as a Width()-bit two's-complement pattern (non-negative), and back.
  // Bit i of Bits() is the bit a bit-serial PE holds in plane i.
  BigInt Bits() const;
  static Fixed FromBits(Format format, const BigInt& bits);
  bool Bit(int i) const;

  friend bool operator==(const Fixed&, const Fixed&) = default;
};

std::string ToString(const Fixed& v);  // "s3.4:0x1f (1.9375)"

// ---- Operations (each follows the rule above; `status` may be null) -------------------
Fixed Add(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
Fixed Sub(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
Fixed Neg(const Fixed& a, Format out, Policy p = {}, Status* status = nullptr);
Fixed Abs(const Fixed& a, Format out, Policy p = {}, Status* status = nullptr);
Fixed Min(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
Fixed Max(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
// Full-width exact product, then rounded and fitted to `out`.
Fixed Mul(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
// Exact quotient a/b rounded and fitted. b == 0: divideByZero is set and the result is
// the format's largest value if a >= 0, its smallest if a < 0 (both policies).
Fixed Div(const Fixed& a, const Fixed& b, Format out, Policy p = {}, Status* status = nullptr);
// Floor of the exact square root (rounding is always Floor), fitted with p.overflow.
// a < 0: invalid is set and the result is 0.
Fixed Sqrt(const Fixed& a, Format out, Policy p = {}, Status* status = nullptr);
// a × 2^k (k may be negative: a right shift), rounded and fitted.
Fixed Shift(const Fixed& a, int k, Format out, Policy p = {}, Status* status = nullptr);
// Rescale between formats.
Fixed Convert(const Fixed& a, Format out, Policy p = {}, Status* status = nullptr);
// Exact comparison of the two values: -1, 0 or +1.
int Compare(const Fixed& a, const Fixed& b);

// From the double's exact (dyadic) value, rounded and fitted. NaN/inf set `invalid` and
// give 0.
Fixed FromDouble(double x, Format out, Policy p = {}, Status* status = nullptr);
// The nearest double (ties to even) to the exact value; exact when Width() <= 53.
double ToDouble(const Fixed& v);

// The common step 2+3, exposed for the bit-serial engine's tests: the exact value
// num × 2^-scale (scale may be negative) rounded and fitted into `out`.
Fixed RoundAndFit(const BigInt& num, int scale, Format out, Policy p, Status* status);

}  // namespace zephyr::fixed
