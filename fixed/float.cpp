#include "fixed/float.h"

#include <fmt/format.h>

#include <cmath>
#include <regex>

#include "fixed/check.h"

namespace zephyr::fixed {

namespace {
int BitLength(const BigInt& n) { return n == 0 ? 0 : static_cast<int>(msb(n)) + 1; }
uint64_t SignedZero(const FloatFormat& f, bool negative) {
  return negative ? uint64_t{1} << (f.Width() - 1) : 0;
}
// A total order on non-NaN values: -0 and +0 both 0 (IEEE comparison) or, with
// `signedZero`, -0 just below +0 (minimumNumber / maximumNumber).
BigInt Key(const FloatFormat& f, uint64_t x, bool signedZero) {
  const FloatParts v = Decode(f, x);
  const uint64_t magnitude = x & (f.Mask() >> 1);
  if (v.cls == FloatParts::Zero) return signedZero && v.sign ? -1 : 0;
  const BigInt k = BigInt(magnitude) * 2;
  return v.sign ? BigInt(-k) : k;
}
uint64_t Canonical(const FloatFormat& f, uint64_t x) {  // flush-to-zero on an input
  const FloatParts v = Decode(f, x);
  return v.cls == FloatParts::Zero ? SignedZero(f, v.sign) : x;
}
}  // namespace

bool FloatFormat::IsValid() const {
  return expBits >= 2 && expBits <= 11 && fracBits >= 1 && fracBits <= 52 && Width() <= 64;
}

std::string FloatFormat::Name() const {
  return fmt::format("e{}m{}{}", expBits, fracBits, subnormals ? "" : "ftz");
}

FloatFormat FloatFormat::Parse(const std::string& text) {
  if (text == "binary32") return Binary32();
  static const std::regex re("e([0-9]+)m([0-9]+)(ftz)?");
  std::smatch m;
  FloatFormat f;
  if (std::regex_match(text, m, re) && m[1].length() <= 3 && m[2].length() <= 3) {
    f = {std::stoi(m[1]), std::stoi(m[2]), !m[3].matched};
    if (f.IsValid()) return f;
  }
  throw UserError(
      fmt::format("float format '{}': expected eXmY or eXmYftz with 2 <= X <= 11, "
                  "1 <= Y <= 52, 1+X+Y <= 64 (e.g. e8m23 = binary32, e5m10, "
                  "e6m10ftz), or binary32",
                  text));
}

uint64_t FloatFormat::CanonicalNaN() const {
  return (uint64_t(MaxField()) << fracBits) | (uint64_t{1} << (fracBits - 1));
}

uint64_t FloatFormat::Infinity(bool negative) const {
  return SignedZero(*this, negative) | (uint64_t(MaxField()) << fracBits);
}

FloatParts Decode(const FloatFormat& f, uint64_t bits) {
  FloatParts v;
  const int m = f.fracBits;
  const uint64_t frac = bits & ((uint64_t{1} << m) - 1);
  const int field = static_cast<int>((bits >> m) & f.MaxField());
  v.sign = (bits >> (f.Width() - 1)) & 1;
  if (field == f.MaxField()) {
    v.cls = frac == 0 ? FloatParts::Inf : FloatParts::NaN;
  } else if (field == 0) {
    if (frac == 0 || !f.subnormals) return v.cls = FloatParts::Zero, v;
    v.cls = FloatParts::Finite, v.sig = frac, v.exp = 1 - f.Bias() - m;
  } else {
    v.cls = FloatParts::Finite, v.sig = frac | (uint64_t{1} << m), v.exp = field - f.Bias() - m;
  }
  return v;
}

bool IsNaN(const FloatFormat& f, uint64_t bits) { return Decode(f, bits).cls == FloatParts::NaN; }

uint64_t RoundToFloat(const FloatFormat& f, bool sign, BigInt n, int e, bool inexact) {
  ZEPHYR_CHECK(n >= 0);
  if (n == 0) {
    ZEPHYR_CHECK(!inexact);
    return SignedZero(f, sign);
  }
  const int m = f.fracBits, emin = 1 - f.Bias();
  int l = BitLength(n) - 1;
  int u = l + e - m;  // the exponent of the result's last place
  if (f.subnormals) u = std::max(u, emin - m);
  if (u <= e) {  // fewer bits than the result keeps: exact, widen
    ZEPHYR_CHECK(!inexact);
    const int s = e - u + 1;
    n <<= s, e -= s;
  }
  const int r = u - e;
  BigInt q = n >> r;
  const BigInt rem = n - (q << r), half = BigInt(1) << (r - 1);
  if (rem > half || (rem == half && (inexact || (q & 1) != 0))) q += 1;
  if (q == (BigInt(1) << (m + 1))) q >>= 1, u += 1;
  if (q == 0) return SignedZero(f, sign);
  int field = 0;
  if (q >= (BigInt(1) << m)) field = u + m + f.Bias();
  if (field >= f.MaxField()) return f.Infinity(sign);
  if (!f.subnormals && field < 1) return SignedZero(f, sign);
  const uint64_t frac = static_cast<uint64_t>(q & ((BigInt(1) << m) - 1));
  return SignedZero(f, sign) | (uint64_t(field) << m) | frac;
}

uint64_t FloatAdd(const FloatFormat& f, uint64_t a, uint64_t b) {
  const FloatParts x = Decode(f, a), y = Decode(f, b);
  if (x.cls == FloatParts::NaN || y.cls == FloatParts::NaN) return f.CanonicalNaN();
  if (x.cls == FloatParts::Inf && y.cls == FloatParts::Inf)
    return x.sign == y.sign ? f.Infinity(x.sign) : f.CanonicalNaN();
  if (x.cls == FloatParts::Inf) return f.Infinity(x.sign);
  if (y.cls == FloatParts::Inf) return f.Infinity(y.sign);
  if (x.cls == FloatParts::Zero && y.cls == FloatParts::Zero)
    return SignedZero(f, x.sign && y.sign);
  if (y.cls == FloatParts::Zero) return RoundToFloat(f, x.sign, x.sig, x.exp, false);
  if (x.cls == FloatParts::Zero) return RoundToFloat(f, y.sign, y.sig, y.exp, false);
  // Far apart: the smaller is only a sticky δ below the larger's widened significand.
  const int p = f.Precision();
  const int lx = x.exp + BitLength(x.sig), ly = y.exp + BitLength(y.sig);
  if (lx - ly > p + 3 || ly - lx > p + 3) {
    const FloatParts& big = lx > ly ? x : y;
    const FloatParts& small = lx > ly ? y : x;
    const int k = 2 * p + 3;
    BigInt n = big.sig << k;
    if (big.sign != small.sign) n -= 1;
    return RoundToFloat(f, big.sign, n, big.exp - k, true);
  }
  const int e = std::min(x.exp, y.exp);
  BigInt sx = x.sig << (x.exp - e), sy = y.sig << (y.exp - e);
  BigInt sum = (x.sign ? BigInt(-sx) : sx) + (y.sign ? BigInt(-sy) : sy);
  if (sum == 0) return SignedZero(f, false);  // exact cancellation: +0 (round to nearest)
  return RoundToFloat(f, sum < 0, abs(sum), e, false);
}

uint64_t FloatSub(const FloatFormat& f, uint64_t a, uint64_t b) {
  return FloatAdd(f, a, b ^ (uint64_t{1} << (f.Width() - 1)));
}

uint64_t FloatMul(const FloatFormat& f, uint64_t a, uint64_t b) {
  const FloatParts x = Decode(f, a), y = Decode(f, b);
  const bool s = x.sign != y.sign;
  if (x.cls == FloatParts::NaN || y.cls == FloatParts::NaN) return f.CanonicalNaN();
  if (x.cls == FloatParts::Inf || y.cls == FloatParts::Inf)
    return x.cls == FloatParts::Zero || y.cls == FloatParts::Zero ? f.CanonicalNaN()
                                                                  : f.Infinity(s);
  if (x.cls == FloatParts::Zero || y.cls == FloatParts::Zero) return SignedZero(f, s);
  return RoundToFloat(f, s, x.sig * y.sig, x.exp + y.exp, false);
}

uint64_t FloatDiv(const FloatFormat& f, uint64_t a, uint64_t b) {
  const FloatParts x = Decode(f, a), y = Decode(f, b);
  const bool s = x.sign != y.sign;
  if (x.cls == FloatParts::NaN || y.cls == FloatParts::NaN) return f.CanonicalNaN();
  if (x.cls == FloatParts::Inf) return y.cls == FloatParts::Inf ? f.CanonicalNaN() : f.Infinity(s);
  if (y.cls == FloatParts::Inf) return SignedZero(f, s);
  if (y.cls == FloatParts::Zero)
    return x.cls == FloatParts::Zero ? f.CanonicalNaN() : f.Infinity(s);
  if (x.cls == FloatParts::Zero) return SignedZero(f, s);
  const int k = f.Precision() + 3 + BitLength(y.sig);
  const BigInt num = x.sig << k;
  const BigInt q = num / y.sig;
  return RoundToFloat(f, s, q, x.exp - y.exp - k, q * y.sig != num);
}

uint64_t FloatSqrt(const FloatFormat& f, uint64_t a) {
  FloatParts x = Decode(f, a);
  if (x.cls == FloatParts::NaN) return f.CanonicalNaN();
  if (x.cls == FloatParts::Zero) return SignedZero(f, x.sign);
  if (x.sign) return f.CanonicalNaN();
  if (x.cls == FloatParts::Inf) return f.Infinity(false);
  if (x.exp % 2 != 0) x.sig <<= 1, x.exp -= 1;
  const int k = f.Precision() + 3;
  const BigInt s = x.sig << (2 * k);
  const BigInt r = boost::multiprecision::sqrt(s);
  return RoundToFloat(f, false, r, x.exp / 2 - k, r * r != s);
}

bool FloatLess(const FloatFormat& f, uint64_t a, uint64_t b) {
  if (IsNaN(f, a) || IsNaN(f, b)) return false;
  return Key(f, a, false) < Key(f, b, false);
}
bool FloatLessEqual(const FloatFormat& f, uint64_t a, uint64_t b) {
  if (IsNaN(f, a) || IsNaN(f, b)) return false;
  return Key(f, a, false) <= Key(f, b, false);
}
bool FloatEqual(const FloatFormat& f, uint64_t a, uint64_t b) {
  if (IsNaN(f, a) || IsNaN(f, b)) return false;
  return Key(f, a, false) == Key(f, b, false);
}

uint64_t FloatMin(const FloatFormat& f, uint64_t a, uint64_t b) {
  if (IsNaN(f, a)) return IsNaN(f, b) ? f.CanonicalNaN() : Canonical(f, b);
  if (IsNaN(f, b)) return Canonical(f, a);
  return Canonical(f, Key(f, a, true) <= Key(f, b, true) ? a : b);
}
uint64_t FloatMax(const FloatFormat& f, uint64_t a, uint64_t b) {
  if (IsNaN(f, a)) return IsNaN(f, b) ? f.CanonicalNaN() : Canonical(f, b);
  if (IsNaN(f, b)) return Canonical(f, a);
  return Canonical(f, Key(f, a, true) >= Key(f, b, true) ? a : b);
}

uint64_t FloatFromFixed(const Fixed& a, const FloatFormat& f) {
  if (a.raw == 0) return 0;
  return RoundToFloat(f, a.raw < 0, abs(a.raw), -a.format.fracBits, false);
}

Fixed FloatToFixed(const FloatFormat& f, uint64_t a, Format out, Policy p, Status* status) {
  const FloatParts x = Decode(f, a);
  switch (x.cls) {
    case FloatParts::NaN:
      if (status) status->invalid = true;
      return Fixed{out, 0};
    case FloatParts::Inf:
      if (status) status->overflow = true;
      return Fixed{out, x.sign ? out.MinRaw() : out.MaxRaw()};
    case FloatParts::Zero:
      return Fixed{out, 0};
    case FloatParts::Finite:
      break;
  }
  // A value 2^Width() times out's unit or more has no low raw bits: clamp its exponent so
  // the intermediate stays small (the wrapped bits are zero either way, overflow is set).
  const int exp = std::min(x.exp, out.Width() - out.fracBits);
  const BigInt num = x.sign ? BigInt(-x.sig) : x.sig;
  return RoundAndFit(num, -exp, out, p, status);
}

double FloatToDouble(const FloatFormat& f, uint64_t a) {
  const FloatParts x = Decode(f, a);
  switch (x.cls) {
    case FloatParts::NaN:
      return std::nan("");
    case FloatParts::Inf:
      return x.sign ? -HUGE_VAL : HUGE_VAL;
    case FloatParts::Zero:
      return x.sign ? -0.0 : 0.0;
    case FloatParts::Finite:
      break;
  }
  const double v = std::ldexp(static_cast<double>(x.sig.convert_to<uint64_t>()), x.exp);
  return x.sign ? -v : v;
}

}  // namespace zephyr::fixed
