// hosts/simd/bounds.cpp — the error-bound arithmetic of the SIMD primary pass
// (hosts/simd/bounds.h, docs/simd.md "Error bounds").
#include "hosts/simd/bounds.h"

#include <algorithm>
#include <cmath>

namespace zephyr::simd {

using fixed::Format;

double PassFormats::Ulp() const { return std::ldexp(1.0, -fracBits); }
double PassFormats::DirError() const { return std::ldexp(0.5, -dirFracBits); }

int CeilLog2(double x) { return x <= 1 ? 0 : int(std::ceil(std::log2(x))); }

int IntBitsFor(double bound) { return std::max(1, CeilLog2(bound + 1)); }

fixed::Fixed Tight(double x, int frac) {
  return fixed::FromDouble(x, Format::Signed(IntBitsFor(std::abs(x)), frac),
                           {fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate});
}

double MulErr(double mx, double ex, double my, double ey, double u) { return mx * ey + my * ex + ex * ey + u; }

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

}  // namespace zephyr::simd
