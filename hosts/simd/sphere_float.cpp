// hosts/simd/sphere_float.cpp — a sphere on the array in bit-serial floating point
// (--number float; docs/simd.md, "Floating point on the array"): the formulas of
// hosts/simd/sphere.cpp (f = centre − eye a uni, tca = f·d, disc = r² − |f×d|²,
// t = tca ∓ √disc) in the pass's float format (bitserial/float.h), with the error bound of
// every quantity for round-to-nearest float operations beside them. t0 and t1 are converted
// to the pass's fixed t (nearest) for the closest-hit fold, the hit and grazing decisions
// are float comparisons with the discriminant.
#include <fmt/format.h>

#include <cmath>

#include "fixed/check.h"
#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::MultiFloat;
using bitserial::UniFloat;
using fixed::FloatFormat;
using fixed::Format;

namespace {

// Relative error of a double computed by one rounded operation (f = centre − eye, r²) and
// of the double unit direction against the exact one (a few operations): generous.
constexpr double kDoubleError = 0x1p-50;

class FloatSphereProgram final : public ObjectProgram {
 public:
  FloatSphereProgram(const Primitive& p, const Vec3& eye, const PassFormats& pf)
      : pf_(pf),
        ff_(*pf.floatFormat),
        f_(std::get<Sphere>(p.shape).centre - eye),
        radius_(std::get<Sphere>(p.shape).radius) {
    for (int k = 0; k < 3; ++k) fBits_[k] = FloatOfDouble(ff_, f_[k]);
    r2Bits_ = FloatOfDouble(ff_, radius_ * radius_);
    Bound(p);
    // |disc| < band, with the band rounded up (a wider band only flags more pixels).
    bandBits_ = FloatAtOrAbove(ff_, b_.grazeBand);
  }

  const ObjectBounds& Bounds() const { return b_; }

  std::vector<PlannedFormat> Formats() const {
    const std::string ff = ff_.Name();
    return {
        {"f (uni), f·d, f×d", pf_.t, fmt::format("float {}: |f·d|, |f×d| <= |f|", ff), ff_},
        {"squares, sum, disc, √disc", pf_.t, fmt::format("float {}: r² − |f×d|², no clamp", ff),
         ff_},
        {"t = tca ∓ root (float)", pf_.t, fmt::format("float {}, then to the fixed t", ff), ff_},
        {"t (fixed, nearest)", pf_.t, "t <= farthest"}};
  }

  Candidate Run(Machine& m, const Directions& dirs, Audit* /*audit: not audited*/) const override {
    const MultiFloat(&d)[3] = dirs.floats;
    const int F = pf_.fracBits;
    const Format T = pf_.t;
    const UniFloat f[3] = {{ff_, fBits_[0]}, {ff_, fBits_[1]}, {ff_, fBits_[2]}}, zero{ff_, 0};
    const MultiFloat tca = Add(Add(Mul(d[0], f[0]), Mul(d[1], f[1])), Mul(d[2], f[2]));
    const MultiFloat c[3] = {Sub(Mul(d[2], f[1]), Mul(d[1], f[2])),
                             Sub(Mul(d[0], f[2]), Mul(d[2], f[0])),
                             Sub(Mul(d[1], f[0]), Mul(d[0], f[1]))};
    const MultiFloat sum = Add(Add(Mul(c[0], c[0]), Mul(c[1], c[1])), Mul(c[2], c[2]));
    const MultiFloat disc = Sub(UniFloat{ff_, r2Bits_}, sum);
    const MultiFloat root = Sqrt(Max(disc, zero));  // a miss's root is 0 (its t is not used)
    const fixed::Policy nearest{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
    const Multi t0 = ToFixed(Sub(tca, root), T, nearest), t1 = ToFixed(Add(tca, root), T, nearest);
    const Multi hither = Broadcast(m, Tight(pf_.hither, F));
    Candidate out;
    out.t = Select(hither < t0, t0, t1, T);  // the far root when the eye is inside
    out.hit = LessEqual(zero, disc) && (hither < out.t);
    // Uncertain: the discriminant within its band of zero, or the near root within its bound
    // of hither — and the far root not certainly behind the eye (as the fixed program).
    const UniFloat band{ff_, bandBits_},
        minusBand{ff_, bandBits_ | (uint64_t{1} << (ff_.Width() - 1))};
    const Multi grazing = Less(disc, band) && Less(minusBand, disc);
    const Multi front = Broadcast(m, Tight(pf_.hither - b_.slack, F)) < t1;
    out.uncertain = (grazing || Near(m, t0 - hither, b_.tError + pf_.Ulp(), F)) && front;
    out.tLow = SubBound(m, t0, b_.slack, T);
    return out;
  }

 private:
  // Error bounds of Run's quantities (docs/simd.md, "Floating point on the array"): each
  // operation adds FloatRoundErr of a bound on its result's magnitude; the discriminant's
  // band is iterated as GrazingBand does, with the squares' magnitudes bounded in the region
  // that matters (|f×d|² <= r² + G).
  void Bound(const Primitive& p) {
    const auto rnd = [&](double magnitude) { return FloatRoundErr(ff_, magnitude); };
    const double u = pf_.Ulp();               // the fixed t's
    const double ed = rnd(1) + kDoubleError;  // a direction component, |d_k| <= 1
    double ep[3], mp[3];  // a product d_j·f_k: its error and its computed magnitude's bound
    for (int k = 0; k < 3; ++k) {
      const double af = std::abs(f_[k]), ef = rnd(af) + af * kDoubleError,
                   exact = (1 + ed) * (af + ef);
      ep[k] = af * ed + ef + ed * ef + rnd(exact);
      mp[k] = exact + rnd(exact);
    }
    const double eTca = ep[0] + ep[1] + ep[2] + rnd(mp[0] + mp[1]) + rnd(mp[0] + mp[1] + mp[2]);
    const double mTca = mp[0] + mp[1] + mp[2] + rnd(mp[0] + mp[1]) + rnd(mp[0] + mp[1] + mp[2]);
    double eCross = 0;
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      eCross = std::max(eCross, ep[i] + ep[j] + rnd(mp[i] + mp[j]));
    }
    const double r2 = radius_ * radius_, eR2 = rnd(r2) + r2 * kDoubleError;
    double g = std::pow(radius_ / 8, 2) * pf_.BandScale(), eDisc = 0;
    for (int it = 0; it < 200; ++it) {
      const double exact = std::sqrt(r2 + g), cm = exact + eCross, cm2 = cm * cm + rnd(cm * cm);
      const double eSquare = SquareErr(exact, eCross, rnd(cm * cm));
      const double eSum = 3 * eSquare + rnd(2 * cm2) + rnd(3 * cm2);
      eDisc = eR2 + eSum + rnd(r2 + eR2 + 3 * cm2 + eSum);
      if (!std::isfinite(eDisc) || 2 * eDisc <= g) break;
      g = std::max(g * 1.25, 2 * eDisc);
    }
    const double mRoot = std::sqrt(r2 + eR2);  // the computed disc <= fl(r²) (rounding is monotone)
    const double mT = mTca + mRoot;
    b_.kind = ShapeKind::kSphere;
    b_.grazeBand = g;
    b_.tError = eTca + eDisc / std::sqrt(g) + rnd(mRoot) + rnd(mT) + u;
    b_.slack = std::max(b_.tError, eTca + std::sqrt(g + eDisc) + rnd(mT) + u) + u;
    b_.farthest = Length(f_) + radius_;
    b_.intBits = IntBitsFor(b_.farthest) + 1;
    if (!std::isfinite(b_.tError) || !std::isfinite(b_.slack) || !(2 * eDisc <= g))
      throw UserError(fmt::format(
          "{}: the sphere's values (|f·d| up to {:.4g}, squares up to {:.4g}) are beyond "
          "the float format {} (largest finite {:.4g}); use more exponent bits "
          "(--float-format)",
          p.where.ToString(), mTca, r2 + g, ff_.Name(), FloatMaxFinite(ff_)));
  }

  PassFormats pf_;
  FloatFormat ff_;
  Vec3 f_;  // eye to centre
  double radius_;
  uint64_t fBits_[3] = {}, r2Bits_ = 0, bandBits_ = 0;
  ObjectBounds b_;
};

}  // namespace

ObjectPlan PlanFloatSphere(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  return PlanOf<FloatSphereProgram>(p, eye, pf);
}

}  // namespace zephyr::simd
