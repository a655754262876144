// fixed/float.h — scalar floating-point formats with a run-time format, and the exact
// reference the bit-serial float (bitserial/float.h) must reproduce bit for bit.
//
// A FloatFormat has `expBits` exponent bits and `fracBits` stored significand bits
// (precision p = fracBits + 1), laid out as IEEE 754 interchange formats are: sign,
// biased exponent, fraction; exponent all ones is infinity (fraction 0) or NaN.
// binary32 is {8, 23}. Rounding is IEEE round-to-nearest, ties to even. Per format:
//   subnormals = true : gradual underflow exactly as IEEE 754;
//   subnormals = false: flush to zero — an input with exponent field 0 is read as ±0,
//                       and a result whose magnitude, rounded to p bits with an unbounded
//                       exponent, is below 2^emin becomes ±0 (the sign kept).
// Every operation computes the exact result (Boost.Multiprecision integers) and rounds it
// once (docs/float.md states the rules). NaN results are the canonical quiet NaN
// (sign 0, exponent all ones, fraction MSB 1), so results compare bit for bit.
#pragma once

#include <cstdint>
#include <string>

#include "fixed/format.h"

namespace zephyr::fixed {

struct FloatFormat {
  int expBits = 8;
  int fracBits = 23;
  bool subnormals = true;

  static FloatFormat Binary32() { return {8, 23, true}; }
  int Width() const { return 1 + expBits + fracBits; }
  int Precision() const { return fracBits + 1; }
  int Bias() const { return (1 << (expBits - 1)) - 1; }
  int MaxField() const { return (1 << expBits) - 1; }  // the inf/NaN exponent field
  // 2 <= expBits <= 11, 1 <= fracBits <= 52, Width() <= 64.
  bool IsValid() const;
  std::string Name() const;  // "e8m23", "e5m10ftz"
  // Parses Name()'s form (also "binary32"); throws UserError naming the text.
  static FloatFormat Parse(const std::string& text);
  uint64_t Mask() const { return Width() == 64 ? ~uint64_t{0} : (uint64_t{1} << Width()) - 1; }
  uint64_t CanonicalNaN() const;
  uint64_t Infinity(bool negative) const;
  friend bool operator==(const FloatFormat&, const FloatFormat&) = default;
};

// A decoded value: value = (-1)^sign × sig × 2^exp for finite values.
struct FloatParts {
  enum Class { Zero, Finite, Inf, NaN } cls = Zero;
  bool sign = false;
  BigInt sig = 0;
  int exp = 0;
};
FloatParts Decode(const FloatFormat& f, uint64_t bits);  // applies flush-to-zero on input
bool IsNaN(const FloatFormat& f, uint64_t bits);

// The exact value (-1)^sign × (n + δ) × 2^e, with δ in (0, 1) when `inexact` and 0
// otherwise, rounded to the format (n > 0, or n == 0 && !inexact for a signed zero).
uint64_t RoundToFloat(const FloatFormat& f, bool sign, BigInt n, int e, bool inexact);

// The operations (a, b are bit patterns of format f; results are bit patterns).
uint64_t FloatAdd(const FloatFormat& f, uint64_t a, uint64_t b);
uint64_t FloatSub(const FloatFormat& f, uint64_t a, uint64_t b);
uint64_t FloatMul(const FloatFormat& f, uint64_t a, uint64_t b);
uint64_t FloatDiv(const FloatFormat& f, uint64_t a, uint64_t b);
uint64_t FloatSqrt(const FloatFormat& f, uint64_t a);
// IEEE comparisons: false if either is NaN; -0 == +0.
bool FloatLess(const FloatFormat& f, uint64_t a, uint64_t b);
bool FloatLessEqual(const FloatFormat& f, uint64_t a, uint64_t b);
bool FloatEqual(const FloatFormat& f, uint64_t a, uint64_t b);
// IEEE 754-2019 minimumNumber / maximumNumber: a NaN operand yields the other operand
// (NaN only if both are), and -0 < +0.
uint64_t FloatMin(const FloatFormat& f, uint64_t a, uint64_t b);
uint64_t FloatMax(const FloatFormat& f, uint64_t a, uint64_t b);
// A fixed-point value rounded to the float format (exact value, one rounding).
uint64_t FloatFromFixed(const Fixed& a, const FloatFormat& f);
// The float's exact value rounded and fitted into `out` as fixed::RoundAndFit does. NaN
// gives 0 and sets status->invalid; ±inf gives out's largest/smallest value and sets
// status->overflow.
Fixed FloatToFixed(const FloatFormat& f, uint64_t a, Format out, Policy p = {},
                   Status* status = nullptr);
// The exact value as a double (finite values of formats up to binary64 precision).
double FloatToDouble(const FloatFormat& f, uint64_t a);

}  // namespace zephyr::fixed
