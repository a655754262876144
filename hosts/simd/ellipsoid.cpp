// hosts/simd/ellipsoid.cpp — an ellipsoid (a transformed NFF sphere) on the array: the
// unit-sphere test in object space along d' = T⁻¹d (not unit), and its error bounds
// (docs/simd.md, "The program", "Error bounds").
//
// tcaN = f·d' = tca·|d'|², cross = f × d', dd = |d'|²; disc = r²|d'|² − |f × d'|²
// = |d'|²·(r² − |v|²) with v the closest-approach vector (Hearn–Baker, d' not unit), and
// t = (tcaN ∓ √disc)/|d'|² by division.
#include <cmath>

#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;

namespace {

class EllipsoidProgram final : public ObjectProgram {
 public:
  EllipsoidProgram(const Primitive& p, const Vec3& eye, const PassFormats& pf)
      : pf_(pf), radius_(std::get<Sphere>(p.shape).radius), fr_(MakeObjectFrame(p, eye)) {
    f_ = std::get<Sphere>(p.shape).centre - fr_.eye;  // object space: a uni
    Bound(p, eye);
    const int F = pf.fracBits;
    for (int k = 0; k < 3; ++k)
      dp_[k] = Format::Signed(IntBitsFor(fr_.rowSum[k] + pf.Ulp() * 4), F);
    const int R = IntBitsFor(radius_ * std::sqrt(fr_.ddMax));
    n_ = Format::Signed(b_.intBits, F);
    clamped_ = Format::Signed(R, F), square_ = Format::Unsigned(2 * R + 2, F);
    disc_ = Format::Signed(2 * R + 2, F), root_ = Format::Unsigned(R + 1, F);
    dd_ = Format::Unsigned(IntBitsFor(fr_.ddMax + 1), F);
    num_ = Format::Signed(b_.intBits + 1, F);
  }

  const ObjectBounds& Bounds() const { return b_; }

  std::vector<PlannedFormat> Formats() const {
    return {{"d' = T⁻¹d (x)", dp_[0], "Σ|T⁻¹ row x|"},
            {"d' = T⁻¹d (y)", dp_[1], "Σ|T⁻¹ row y|"},
            {"d' = T⁻¹d (z)", dp_[2], "Σ|T⁻¹ row z|"},
            {"f·d', f×d'", n_, "|f|·|d'|"},
            {"cross, clamped", clamped_, "only |f×d'| <= r·|d'| can hit; larger saturate (a miss)"},
            {"squares, r²|d'|²", square_, "three squares of the clamped cross product"},
            {"discriminant", disc_, "r²|d'|² − |f×d'|²"},
            {"root √disc", root_, "half the discriminant's integer bits"},
            {"|d'|²", dd_, "Σ_k (Σ|T⁻¹ row k|)²"},
            {"f·d' ∓ root", num_, "one bit above f·d'"},
            {"t = (f·d' ∓ root)/|d'|²", pf_.t, "by division"}};
  }

  Candidate Run(Machine& m, const Directions& dirs, Audit* audit) const override {
    const Multi(&d)[3] = dirs.fixed;
    const int F = pf_.fracBits;
    const Fixed f[3] = {Tight(f_.x, F), Tight(f_.y, F), Tight(f_.z, F)};
    // d' = T⁻¹'s 3×3 times d: nine multiplies by uni constants.
    Multi dp[3];
    for (int k = 0; k < 3; ++k) {
      const Fixed a[3] = {Tight(fr_.a[k][0], F), Tight(fr_.a[k][1], F), Tight(fr_.a[k][2], F)};
      dp[k] = Dot3(d, a, dp_[k]);
    }
    const Multi tcaN = Dot3(dp, f, n_);
    const Multi sum = CrossSquared(m, dp, f, n_, clamped_, square_);
    const Multi dd = Add(Add(Square(dp[0], dd_), Square(dp[1], dd_), dd_), Square(dp[2], dd_), dd_);
    const Multi r2dd = Mul(dd, Uni{Tight(radius_ * radius_, F)}, square_);
    const Multi disc = Sub(r2dd, sum, disc_);
    const Multi root = Sqrt(disc, root_);
    const Multi num0 = Sub(tcaN, root, num_), num1 = Add(tcaN, root, num_);
    const Multi hd =
        pf_.hither > 0 ? Mul(dd, Uni{Tight(pf_.hither, F)}, num_) : Broadcast(m, Fixed{num_, 0});
    const Multi num = Select(hd < num0, num0, num1, num_);
    Candidate out;
    out.hit = (Zero(m) <= disc) && (hd < num);
    out.uncertain = b_.alwaysUncertain
                        ? (Zero(m) <= num1)
                        : Near(m, disc, b_.grazeBand, F) ||
                              Near(m, num0 - hd, b_.tError * fr_.ddMax + pf_.Ulp(), F);
    const Multi numPos = Max(num, Zero(m), num_);
    Where(out.hit || out.uncertain, [&] { out.t = Div(numPos, dd, pf_.t, kSaturate); });
    out.tLow = SubBound(m, out.t, b_.slack, pf_.t);
    if (audit) Record(*audit, dp, tcaN, dd, disc, root, num0, num1, out);
    return out;
  }

 private:
  // The audit's record (hosts/simd/audit.h): d', tcaN and |d'|² everywhere; the discriminant
  // where its computed value is >= −G; the root and both numerators tcaN ∓ root where disc >= G; a
  // certain hit's t; an uncertain candidate's t >= the true hit − slack. Nothing where the bounds
  // do not close (always uncertain).
  void Record(Audit& audit, const Multi (&dp)[3], const Multi& tcaN, const Multi& dd,
              const Multi& disc, const Multi& root, const Multi& num0, const Multi& num1,
              const Candidate& out) const {
    if (b_.alwaysUncertain) return;
    const int64_t n = dd.GetMachine().VirtualPes();
    // G, and G as the program compares with it (rounded to nearest: Near).
    const double u = pf_.Ulp(), g = b_.grazeBand, gt = fixed::ToDouble(Tight(g, pf_.fracBits));
    const std::vector<double> dv = Audit::Values(disc), hit = Audit::Values(out.hit),
                              unsure = Audit::Values(out.uncertain);
    std::vector<double> eDisc(n, Audit::kNoClaim), eRoot(n, Audit::kNoClaim),
        eNum(n, Audit::kNoClaim), eT(n, Audit::kNoClaim), slack(n, Audit::kNoClaim);
    for (int64_t pe = 0; pe < n; ++pe) {
      if (dv[pe] >= -gt) eDisc[pe] = e_.disc;
      if (dv[pe] >= gt) eRoot[pe] = e_.disc / std::sqrt(g) + u, eNum[pe] = e_.num;
      if (hit[pe] && !unsure[pe]) eT[pe] = b_.tError;
      if (unsure[pe]) slack[pe] = b_.slack;
    }
    audit.constants = {{"grazeBand", g},
                       {"crossError", e_.cross},
                       {"clampRange", std::ldexp(1.0, clamped_.intBits)},
                       {"hither", pf_.hither}};
    for (int k = 0; k < 3; ++k)
      audit.Record(std::string("d'") + "xyz"[k], dp[k], Audit::Where({}, e_.dp[k], n));
    audit.Record("tcaN", tcaN, Audit::Where({}, e_.tcaN, n));
    audit.Record("|d'|²", dd, Audit::Where({}, e_.dd, n));
    audit.Record("disc", disc, eDisc);
    audit.Record("root", root, eRoot);
    audit.Record("num0", num0, eNum);
    audit.Record("num1", num1, eNum);
    audit.Record("t", out.t, eT);
    audit.Record("t - slack", out.t, slack, Audit::Side::kAbove);
  }

  // The bounds: d' from nine products, then tcaN, the cross and |d'|² from products of
  // d' (bounded by the row sums) by f; the band from GrazingBand at r²|d'|²; t's error
  // through the division by |d'|² >= ddMin (σ_min(T⁻¹) >= 1/‖T‖_F).
  void Bound(const Primitive& p, const Vec3& eye) {
    const double u = pf_.Ulp(), dd = pf_.DirError();
    b_.kind = ShapeKind::kSphere;
    b_.transformed = true;
    double eDp[3], mDp[3];
    for (int k = 0; k < 3; ++k) {
      eDp[k] = 0;
      for (int j = 0; j < 3; ++j) eDp[k] += MulErr(1, dd, std::abs(fr_.a[k][j]), u / 2, u);
      mDp[k] = fr_.rowSum[k] + eDp[k];
    }
    double eTcaN = 0, eCross = 0, eDd = 0;
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      eTcaN += MulErr(mDp[k], eDp[k], std::abs(f_[k]), u / 2, u);
      eCross = std::max(eCross, MulErr(mDp[j], eDp[j], std::abs(f_[i]), u / 2, u) +
                                    MulErr(mDp[i], eDp[i], std::abs(f_[j]), u / 2, u));
      eDd += 2 * mDp[k] * eDp[k] + eDp[k] * eDp[k] + u;
    }
    const double r = radius_;
    const double ddMax = fr_.ddMax + eDd;
    const double ddMin = std::pow((1 - std::sqrt(3.0) * dd) / fr_.forwardNorm, 2) - eDd;
    const double eR2dd = r * r * eDd + ddMax * u / 2 + u;
    const auto [band, eDisc] = GrazingBand(
        r * r * ddMax, std::pow(r * std::sqrt(std::max(ddMin, 0.0)) / 8, 2) * pf_.BandScale(),
        eCross, eR2dd, std::ldexp(1.0, IntBitsFor(r * std::sqrt(fr_.ddMax))), u);
    const Vec3 centre = p.transform->ApplyPoint(std::get<Sphere>(p.shape).centre);
    b_.farthest = Length(centre - eye) + r * fr_.forwardNorm;
    b_.intBits = IntBitsFor(std::max(b_.farthest, (Length(f_) + r) * std::sqrt(ddMax)) + 1) + 1;
    if (!(ddMin > 0)) {
      b_.alwaysUncertain = true;
      b_.tError = b_.slack = kInf;
      return;
    }
    b_.grazeBand = band;
    const double eNum = eTcaN + eDisc / std::sqrt(b_.grazeBand) + u;
    e_ = {{eDp[0], eDp[1], eDp[2]}, eTcaN, eCross, eDd, eDisc, eNum};
    b_.tError = eNum / ddMin + b_.farthest * eDd / ddMin + u;
    b_.slack = b_.tError + 2 * std::sqrt(b_.grazeBand + eDisc) / ddMin + u;
  }

  PassFormats pf_;
  double radius_;
  ObjectFrame fr_;
  Vec3 f_;  // object-space eye to centre
  Format dp_[3], n_, clamped_, square_, disc_, root_, dd_, num_;
  struct {
    // Error bounds (Bound()) of d' = T⁻¹d, f·d', each cross component, |d'|², disc and the
    // numerators f·d' ∓ root (object-space units and their squares, as each quantity has).
    double dp[3] = {}, tcaN = 0, cross = 0, dd = 0, disc = 0, num = 0;
  } e_;
  ObjectBounds b_;
};

}  // namespace

ObjectExtent EllipsoidExtent(const Primitive& p, const Vec3& eye) {
  const Sphere& s = std::get<Sphere>(p.shape);
  const ObjectFrame fr = MakeObjectFrame(p, eye);
  const Vec3 centre = p.transform->ApplyPoint(s.centre);
  // Smallest semi-axis r·σ_min(T) >= r / ‖T⁻¹‖_F.
  return {Length(centre - eye) + s.radius * fr.forwardNorm, s.radius / InverseFrobenius(p)};
}

ObjectPlan PlanEllipsoid(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  return PlanOf<EllipsoidProgram>(p, eye, pf);
}

}  // namespace zephyr::simd
