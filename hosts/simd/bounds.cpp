// hosts/simd/bounds.cpp — the error-bound arithmetic of the SIMD primary pass
// (hosts/simd/bounds.h, docs/simd.md "Error bounds").
#include "hosts/simd/bounds.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fixed/check.h"

namespace zephyr::simd {

using fixed::Format;

double PassFormats::Ulp() const { return std::ldexp(1.0, -fracBits); }
double PassFormats::DirError() const { return std::ldexp(0.5, -dirFracBits); }

int CeilLog2(double x) { return x <= 1 ? 0 : int(std::ceil(std::log2(x))); }

int IntBitsFor(double bound) { return std::max(1, CeilLog2(bound + 1)); }

fixed::Fixed Tight(double x, int frac) {
  const Format f = Format::Signed(IntBitsFor(std::abs(x)), frac);
  // A value no format of the engine holds (1/r of a sphere of radius 1e-30: 101 integer bits
  // beside 40 fraction bits) is the scene's, not a bug: a UserError, never an abort.
  if (!f.IsValid())
    throw UserError(fmt::format(
        "the value {:.6g} needs {} integer and {} fraction bits, more than the engine's widest "
        "number ({} bits)",
        x, f.intBits, f.fracBits, fixed::kMaxWidth));
  return fixed::FromDouble(x, f, {fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate});
}

double MulErr(double mx, double ex, double my, double ey, double u) {
  return mx * ey + my * ex + ex * ey + u;
}

double SquareErr(double m, double e, double u) { return 2 * m * e + e * e + u; }

std::pair<double, double> GrazingBand(double r2, double floorBand, double eCross, double eR2,
                                      double clampRange, double u) {
  double g = floorBand, eDisc = 0;
  for (int it = 0; it < 50; ++it) {
    const double cm = std::min(clampRange, std::sqrt(r2 + g)) + eCross;
    eDisc = eR2 + 3 * (2 * cm * eCross + eCross * eCross + u);
    if (2 * eDisc <= g) break;
    g = std::max(g * 1.25, 2 * eDisc);
  }
  return {g, eDisc};
}

uint64_t FloatOfDouble(const fixed::FloatFormat& f, double x) {
  int e = 0;
  const double mant = std::frexp(std::abs(x), &e);  // |x| = mant·2^e, mant in [0.5, 1)
  const int64_t n = int64_t(std::ldexp(mant, 53));  // exact: 53 significant bits
  return fixed::RoundToFloat(f, std::signbit(x), fixed::BigInt(n), n == 0 ? 0 : e - 53, false);
}

uint64_t FloatAtOrAbove(const fixed::FloatFormat& f, double x) {
  uint64_t b = FloatOfDouble(f, x);
  if (fixed::FloatToDouble(f, b) >= x) return b;
  // Below x: the next value up (the patterns of one sign are ordered as integers; a
  // negative b below x is not a zero). A flush-to-zero format reads a subnormal as 0: from
  // +0 the next value up is 2^emin.
  if (x < 0) return b - 1;
  const uint64_t up = b + 1;
  return !f.subnormals && (up >> f.fracBits) == 0 ? uint64_t{1} << f.fracBits : up;
}

double FloatMaxFinite(const fixed::FloatFormat& f) {
  return std::ldexp(2.0 - std::ldexp(1.0, -f.fracBits), f.Bias());
}

double FloatRoundErr(const fixed::FloatFormat& f, double m) {
  if (!(m < FloatMaxFinite(f))) return kInf;
  const int emin = 1 - f.Bias();
  const double underflow =
      f.subnormals ? std::ldexp(1.0, emin - f.fracBits - 1) : std::ldexp(1.0, emin);
  return std::ldexp(m, -f.Precision()) + underflow;
}

LinearForm MakeLinear(const Vec3& c, const PassFormats& pf) {
  LinearForm l;
  l.c = c;
  double l1 = 0;
  for (int k = 0; k < 3; ++k) {
    l.err += MulErr(1, pf.DirError(), std::abs(c[k]), pf.Ulp() / 2, pf.Ulp());
    l1 += std::abs(c[k]);
  }
  l.max = Length(c) + l.err;
  l.format = Format::Signed(IntBitsFor(l1 + l.err + pf.Ulp()), pf.fracBits);
  return l;
}

ConeDivision PlanDivision(double eN, double eD, double tFar, double target, double freeThreshold,
                          int frac) {
  const double u = std::ldexp(1.0, -frac);
  ConeDivision v;
  v.eN = eN, v.eD = eD;
  v.dStar = std::max({4 * eD, eD + (eN + 2 * tFar * eD) / target, freeThreshold});
  const double eta = eD / v.dStar, eps = eN / v.dStar;
  v.tCut = tFar * (1 + eta) + eps + u;  // floor division: N/D in [t, t + u)
  v.tRange = (v.tCut + eps) / (1 - eta);
  v.tError = eps + v.tRange * eta + u;
  v.out = Format::Signed(IntBitsFor(v.tCut) + 1, frac);
  return v;
}

}  // namespace zephyr::simd
