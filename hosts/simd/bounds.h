// hosts/simd/bounds.h — the error-bound arithmetic of the SIMD primary pass (docs/simd.md,
// "Error bounds"): the pass-wide formats, the narrowest format of a value, and sound bounds
// on the error of a floor-rounded product, a square, a linear form of the direction and a
// discriminant's grazing band. Host-only (doubles); each primitive kind's file
// (hosts/simd/{sphere,ellipsoid,polygon,cone}.cpp) builds its bounds from these.
#pragma once

#include <limits>
#include <optional>
#include <utility>

#include "fixed/float.h"
#include "fixed/format.h"
#include "hosts/scene/geometry.h"

namespace zephyr::simd {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The pass-wide formats every primitive's program shares.
struct PassFormats {
  int fracBits = 0;     // F: fraction bits of every length, product and t
  int dirFracBits = 0;  // Fd: fraction bits of the direction components
  fixed::Format t;      // t (and the distances it is built from)
  double hither = 0;    // max(camera hither, 0)
  // The ulp the bounds' nominal sizes refer to (the grazing bands' radius-fraction floors, a
  // cone's target t error): 0 = this pass's own. A refine pass at wider formats keeps the
  // first pass's nominal t error and shrinks those floors by Ulp()/nominal.
  double nominalUlp = 0;
  // --number float: the intersections' float format (else unset).
  std::optional<fixed::FloatFormat> floatFormat;
  double Ulp() const;       // 2^-F: a floor-rounded result's error
  double DirError() const;  // 2^-Fd / 2: a direction component's rounding error
  double NominalUlp() const { return nominalUlp > 0 ? nominalUlp : Ulp(); }
  double BandScale() const { return Ulp() / NominalUlp(); }  // 1 for a first pass
};

// ceil(log2 x), 0 for x <= 1.
int CeilLog2(double x);
// Integer bits for values of magnitude up to `bound` (at least 1).
int IntBitsFor(double bound);

// A uni constant rounded to nearest in the narrowest format with `frac` fraction bits that
// holds it (a multiply by a uni costs one row per one bit).
fixed::Fixed Tight(double x, int frac);

// The error of a floor-rounded product x·y when |x| <= mx with error ex and |y| <= my with
// error ey (u: the result's ulp).
double MulErr(double mx, double ex, double my, double ey, double u);

// The error of a floor-rounded square x² when |x| <= m exactly and x has error e.
double SquareErr(double m, double e, double u);

// The grazing band G of a discriminant r2 − Σ_k c_k² (three clamped cross components, each
// with error eCross; r2's own error eR2) and the discriminant's error bound in the region
// that matters: {G, eDisc}. A pixel whose computed disc is <= −G is a certain miss, one >= G
// a certain hit whose root is within eDisc/√G; in between it is grazing. In that region
// Σ c² <= r2 + G, so |c| <= √(r2 + G) + eCross (below the clamp's range `clampRange`, or
// saturation only moves c towards the boundary), which bounds the squares' error.
// G >= 2·eDisc, and at least `floorBand`; found by iterating G (it only grows).
std::pair<double, double> GrazingBand(double r2, double floorBand, double eCross, double eR2,
                                      double clampRange, double u);

// --number float (docs/simd.md, "Floating point on the array"): the float format's value of a
// double rounded to nearest (ties to even), and the least value >= x (x finite), as bit
// patterns of f.
uint64_t FloatOfDouble(const fixed::FloatFormat& f, double x);
uint64_t FloatAtOrAbove(const fixed::FloatFormat& f, double x);
// The largest finite value of f.
double FloatMaxFinite(const fixed::FloatFormat& f);
// A sound bound on the error of one float operation of f (round to nearest) whose exact
// result has magnitude <= m: 2^-p·m (half an ulp relative, p = fracBits + 1) plus
// the underflow's absolute error (half the subnormal spacing, or 2^emin where f flushes to
// zero); +inf when m reaches f's largest finite value (the result may overflow).
double FloatRoundErr(const fixed::FloatFormat& f, double m);

// One division t = N/D (a cone's roots, here and in the wavefront, hosts/wavefront), decided
// per PE against a threshold D* on |D| (docs/simd.md, "Error bounds", cone). With
// |N − N_exact| <= eN and |D − D_exact| <= eD:
//  - |D| >= D*: |t − t_exact| <= (eN + |t_exact|·eD)/|D| <= eps + |t_exact|·eta (eta =
//    eD/D*, eps = eN/D*). A computed |t| >= tCut means |t_exact| >= tFar (no point of the
//    cone is that far: the root is not a hit); below it |t_exact| <= tRange and the error is
//    at most tError.
//  - |D| < D*: the root is no hit when certainly outside [tNear, tFar]; else the PE is
//    uncertain.
// D* is the largest of 4·eD, the one that makes the error `target` at tFar, and
// `freeThreshold` (a bound |D| is known to exceed anyway); frac: the quotient's fraction bits.
struct ConeDivision {
  double eN = 0, eD = 0, dStar = 0, tCut = 0, tRange = 0, tError = 0;
  fixed::Format out;  // the quotient (holds 2·tCut; saturation means "beyond")
};
ConeDivision PlanDivision(double eN, double eD, double tFar, double target, double freeThreshold,
                          int frac);

// One linear form c·d of the direction with uni coefficients c (rounded to nearest): the
// computed value is within `err` of the exact c·d̂ along the exact unit direction, and
// |value| <= max; `format` holds it.
struct LinearForm {
  Vec3 c;
  double max = 0, err = 0;
  fixed::Format format;
};
LinearForm MakeLinear(const Vec3& c, const PassFormats& pf);

}  // namespace zephyr::simd
