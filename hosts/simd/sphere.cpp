// hosts/simd/sphere.cpp — a sphere on the array: Hearn–Baker through the cross product, and
// the error bound of every quantity beside it (docs/simd.md, "The program", "Error bounds").
//
// With f = centre − eye (a uni) and the unit direction d: tca = f·d, and |f − tca·d| =
// |f × d|, so disc = r² − |f × d|² and t = tca ∓ √disc. Only |f × d| <= r can hit: each
// cross component is clamped to r's integer bits (saturation there is a miss, not an error).
#include <cmath>

#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using fixed::Fixed;
using fixed::Format;

namespace {

class SphereProgram final : public ObjectProgram {
 public:
  SphereProgram(const Sphere& s, const Vec3& eye, const PassFormats& pf)
      : pf_(pf), f_(s.centre - eye), radius_(s.radius) {
    const int F = pf.fracBits, R = IntBitsFor(s.radius);
    clamped_ = Format::Signed(R, F), square_ = Format::Unsigned(2 * R + 2, F);
    disc_ = Format::Signed(2 * R + 2, F), root_ = Format::Unsigned(R + 1, F);
    Bound();
  }

  const ObjectBounds& Bounds() const { return b_; }

  std::vector<PlannedFormat> Formats() const {
    return {{"eye-to-centre f (uni), tca = f·d, f×d", pf_.t, "|f·d|, |f×d| <= |f|"},
            {"cross, clamped", clamped_, "only |f×d| <= r can hit; larger saturate (a miss)"},
            {"squares, their sum", square_, "three squares of the clamped cross product"},
            {"discriminant r²−|f×d|²", disc_, "difference of the above"},
            {"root √disc", root_, "half the discriminant's integer bits"},
            {"t = tca ∓ root", pf_.t, "t <= farthest"}};
  }

  Candidate Run(Machine& m, const Directions& dirs, Audit* audit) const override {
    const Multi(&d)[3] = dirs.fixed;
    const int F = pf_.fracBits;
    const Format T = pf_.t, L = pf_.t;
    const Fixed f[3] = {Tight(f_.x, F), Tight(f_.y, F), Tight(f_.z, F)};
    const Multi tca = Dot3(d, f, L);
    const Multi sum = CrossSquared(m, d, f, L, clamped_, square_);
    const Multi disc = Sub(Broadcast(m, Tight(radius_ * radius_, F)), sum, disc_);
    const Multi root = Sqrt(disc, root_);
    const Multi t0 = Sub(tca, root, T), t1 = Add(tca, root, T);
    const Multi hither = Broadcast(m, Tight(pf_.hither, F));
    Candidate out;
    out.t = Select(hither < t0, t0, t1, T);  // the far root when the eye is inside
    out.hit = (Zero(m) <= disc) && (hither < out.t);
    // Uncertain: the discriminant within its bound of zero, or the near root within its
    // bound of hither — and the far root not certainly behind the eye.
    const Multi front = Broadcast(m, Tight(pf_.hither - b_.slack, F)) < t1;
    out.uncertain =
        (Near(m, disc, b_.grazeBand, F) || Near(m, t0 - hither, b_.tError + pf_.Ulp(), F)) && front;
    out.tLow = SubBound(m, t0, b_.slack, T);
    if (audit) Record(*audit, tca, disc, root, t0, out);
    return out;
  }

 private:
  // The audit's record (hosts/simd/audit.h): each quantity with the bound Bound() claims and
  // where it claims it — tca everywhere, the discriminant where its computed value is >= −G
  // (the cross components within their clamp: the audit's exact side checks that), the root
  // and, through it, a certain hit's t where disc >= G; t0 >= the true hit − slack where the
  // candidate is uncertain.
  void Record(Audit& audit, const Multi& tca, const Multi& disc, const Multi& root, const Multi& t0,
              const Candidate& out) const {
    const int64_t n = tca.GetMachine().VirtualPes();
    // G, and G as the program compares with it (rounded to nearest: Near).
    const double u = pf_.Ulp(), g = b_.grazeBand, gt = fixed::ToDouble(Tight(g, pf_.fracBits));
    const std::vector<double> dv = Audit::Values(disc), hit = Audit::Values(out.hit),
                              unsure = Audit::Values(out.uncertain);
    std::vector<double> eDisc(n, Audit::kNoClaim), eRoot(n, Audit::kNoClaim),
        eT(n, Audit::kNoClaim), slack(n, Audit::kNoClaim);
    for (int64_t pe = 0; pe < n; ++pe) {
      if (dv[pe] >= -gt) eDisc[pe] = e_.disc;
      if (dv[pe] >= gt) eRoot[pe] = e_.disc / std::sqrt(g) + u;
      if (hit[pe] && !unsure[pe]) eT[pe] = b_.tError;
      if (unsure[pe]) slack[pe] = b_.slack;
    }
    audit.constants = {{"grazeBand", g},
                       {"crossError", e_.cross},
                       {"clampRange", std::ldexp(1.0, clamped_.intBits)}};
    audit.Record("tca", tca, Audit::Where({}, e_.tca, n));
    audit.Record("disc", disc, eDisc);
    audit.Record("root", root, eRoot);
    audit.Record("t", out.t, eT);
    audit.Record("t0 - slack", t0, slack, Audit::Side::kAbove);
  }

  // The bounds of Run's quantities: tca and each cross component from the products of the
  // rounded direction by the rounded f; the discriminant's band from GrazingBand.
  void Bound() {
    const double u = pf_.Ulp(), dd = pf_.DirError();
    b_.kind = ShapeKind::kSphere;
    double eTca = 0, eCross = 0;
    for (int k = 0; k < 3; ++k) {
      eTca += MulErr(1, dd, std::abs(f_[k]), u / 2, u);
      eCross = std::max(eCross, MulErr(1, dd, std::abs(f_[(k + 1) % 3]), u / 2, u) +
                                    MulErr(1, dd, std::abs(f_[(k + 2) % 3]), u / 2, u));
    }
    const auto [band, eDisc] =
        GrazingBand(radius_ * radius_, std::pow(radius_ / 8, 2) * pf_.BandScale(), eCross, u / 2,
                    std::ldexp(1.0, IntBitsFor(radius_)), u);
    e_ = {eTca, eCross, eDisc};
    b_.grazeBand = band;
    b_.tError = eTca + eDisc / std::sqrt(b_.grazeBand) + u;
    b_.slack = std::max(b_.tError, eTca + std::sqrt(b_.grazeBand + eDisc)) + u;
    b_.farthest = Length(f_) + radius_;
    b_.intBits = IntBitsFor(b_.farthest) + 1;
  }

  PassFormats pf_;
  Vec3 f_;  // eye to centre
  double radius_;
  Format clamped_, square_, disc_, root_;
  struct {
    // Error bounds (Bound()) of tca and of each cross component (scene units), of disc (units²).
    double tca = 0, cross = 0, disc = 0;
  } e_;
  ObjectBounds b_;
};

}  // namespace

ObjectExtent SphereExtent(const Primitive& p, const Vec3& eye) {
  const Sphere& s = std::get<Sphere>(p.shape);
  return {Length(s.centre - eye) + s.radius, s.radius};
}

ObjectPlan PlanSphere(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  return PlanOf<SphereProgram>(std::get<Sphere>(p.shape), eye, pf);
}

}  // namespace zephyr::simd
