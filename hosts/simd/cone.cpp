// hosts/simd/cone.cpp — an open truncated cone or cylinder (NFF `c`) on the array, plain or
// transformed: linear forms of the direction, the stable quadratic, two divisions decided
// per PE, the height test, and beside them the error bound of every quantity (docs/simd.md,
// "The program", cones, and "Error bounds").
#include <algorithm>
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

// Per-PE error ladders (docs/simd.md, "Error bounds", cones). The object-wide bounds hold at
// the edge of what is certified: the root's error eDisc/√G at the grazing band's edge and a
// quotient's (eN + |t|·eD)/|D| at the divisor's threshold D*. Most PEs are far from both: rung
// j of the discriminant, computed disc >= 4^j·G, has √disc within eDisc/(2^j·√G); rung k of a
// divisor, |D| >= 4^k·D*, divides the quotient's error by 4^k. Each PE takes the tightest rung
// whose conditions hold (masked broadcasts of uni constants: no division), for its t margin
// (near ties, hither) and its height margin (the rims).
constexpr int kDiscRungs = 4, kDivRungs = 4;

struct ConeLadder {
  double margin[kDiscRungs][kDivRungs] = {};  // |t − t_exact| + u at rung (j, k)
  double height[kDiscRungs][kDivRungs] = {};  // |s − s_exact| + u at rung (j, k)
  Format format;                              // holds every margin and height
};

// An open truncated cone (NFF `c`) as the array tests it: everything the host folds into uni
// constants, and the error analysis (docs/simd.md: "The program", cones, and "Error bounds").
// In object space (ray o' + t·d', d' = T⁻¹d, so t is the world t) with unit axis a,
// w = o' − base, w⊥ = w − (w·a)a, the radius rw = r0 + σ(w·a) at the eye's height and
// σ = (r1 − r0)/h, the roots solve A t² + 2β t + C = 0 with
//   A = |d'⊥|² − (σ·d'·a)²,  β = w⊥·d'⊥ − σ·rw·(d'·a),  C = |w⊥|² − rw²,
//   β² − AC = |rw·d'⊥ − σ(d'·a)·w⊥|² − (d'·(w × a))²     (the stable discriminant)
// Every quantity inside a square is a linear form in the world direction d (T⁻¹ folded into
// the coefficients). Roots: Q = |β| + √disc, t = −sgn(β)·Q/A and −sgn(β)·C/Q, valid where
// hither < t and the height s = w·a + t·(d'·a) lies in [sLo, sHi].
struct ConeSetup {
  LinearForm da, g, u[3], e[3], q, beta;
  double C = 0, wa = 0, sLo = 0, sHi = 0;
  bool empty = false;  // no height has a non-negative radius: never hit
  Format aFormat, discFormat, sum3A, sum3Disc, rootFormat, qFormat;
  double eA = 0, eDisc = 0, grazeBand = 0, eRoot = 0, eQ = 0;
  // The error of Q where the computed disc >= 4^j·G (rung j of the ladders; [0] = eQ):
  // eβ + e_disc/(2^j·√G) + u, as |√x − √y| <= |x − y|/√x.
  double eQAt[kDiscRungs] = {};
  ConeDivision divA, divC;  // t = Q/A and t = C/Q
  ConeLadder ladder[2];     // per-PE margins of each division's root (rung (0, 0): the bounds')
  Format sFormat[2];
  double tFar = 0, tNear = 0;
  bool degenerate = false;
  bool rootsOrdered = false;  // G − e_disc > eβ²: a certain C/Q hit hides Q/A (ConeProgram::Run) //
                              // the bounds do not close at these widths: always uncertain
};

// ‖T‖₂ <= √(‖T‖₁‖T‖∞) (tighter than the Frobenius norm for rotations and scales); 1 without
// a transform.
double Spectral(const Primitive& p, const ObjectFrame& fr) {
  if (!p.transform) return 1;
  double n1 = 0, nInf = 0;
  for (int i = 0; i < 3; ++i) {
    double row = 0, col = 0;
    for (int j = 0; j < 3; ++j)
      row += std::abs(p.transform->m[i][j]), col += std::abs(p.transform->m[j][i]);
    nInf = std::max(nInf, row), n1 = std::max(n1, col);
  }
  return std::min(fr.forwardNorm, std::sqrt(n1 * nInf));
}

// The world-space bounding sphere of the cone seen from the eye: every hit has
// near <= t <= far · (1 + 1e-12) (`far` includes that margin).
struct ConeReach {
  double near = 0, far = 0;
};
ConeReach Reach(const Primitive& p, const Vec3& eye, double spectral) {
  const Cone& cone = std::get<Cone>(p.shape);
  const Vec3 axisFull = cone.apex - cone.base;
  const double h = Length(axisFull);
  const Vec3 a = axisFull / h;
  const double halfH = h / 2, rMax = std::max(std::abs(cone.baseRadius), std::abs(cone.apexRadius));
  const Vec3 mid = cone.base + a * halfH;
  const Vec3 midWorld = p.transform ? p.transform->ApplyPoint(mid) : mid;
  const double reach = std::sqrt(halfH * halfH + rMax * rMax) * spectral;
  return {std::max(0.0, Length(midWorld - eye) - reach),
          (Length(midWorld - eye) + reach) * (1 + 1e-12)};
}

// The geometry and the linear forms of d: wa, C, the heights [sLo, sHi], da, g, u, e, q, β.
void SetUpForms(ConeSetup& cs, const Cone& cone, const ObjectFrame& fr, const PassFormats& pf) {
  const Vec3 axisFull = cone.apex - cone.base;
  const double h = Length(axisFull);
  const Vec3 a = axisFull / h;
  const double sigma = (cone.apexRadius - cone.baseRadius) / h;
  const Vec3 w = fr.eye - cone.base;
  cs.wa = Dot(w, a);
  const Vec3 wPerp = w - a * cs.wa;
  const double rw = cone.baseRadius + sigma * cs.wa;
  cs.C = Dot(wPerp, wPerp) - rw * rw;
  // Heights with a non-negative radius within [0, h] (the other nappe is not the cone).
  cs.sLo = 0, cs.sHi = h;
  if (sigma > 0) cs.sLo = std::max(cs.sLo, -cone.baseRadius / sigma);
  if (sigma < 0) cs.sHi = std::min(cs.sHi, -cone.baseRadius / sigma);
  if (sigma == 0 && cone.baseRadius < 0) cs.empty = true;
  if (cs.sLo > cs.sHi) cs.empty = true;
  // Coefficients over the world direction: x·d' = (A3ᵀx)·d.
  auto pull = [&](const Vec3& x) {
    double r[3];
    for (int j = 0; j < 3; ++j) r[j] = fr.a[0][j] * x.x + fr.a[1][j] * x.y + fr.a[2][j] * x.z;
    return Vec3{r[0], r[1], r[2]};
  };
  const Vec3 cDa = pull(a);
  cs.da = MakeLinear(cDa, pf);
  cs.g = MakeLinear(cDa * sigma, pf);
  for (int k = 0; k < 3; ++k) {
    double row[3];  // row k of the projector I − aaᵀ
    for (int j = 0; j < 3; ++j) row[j] = (k == j ? 1.0 : 0.0) - a[k] * a[j];
    const Vec3 cU = pull(Vec3{row[0], row[1], row[2]});
    cs.u[k] = MakeLinear(cU, pf);
    cs.e[k] = MakeLinear(cU * rw - cDa * (sigma * wPerp[k]), pf);
  }
  cs.q = MakeLinear(pull(Cross(w, a)), pf);
  cs.beta = MakeLinear(pull(wPerp - a * (sigma * rw)), pf);
}

// The errors and formats of A = Σu² − g² and disc = Σe² − q² (squares of computed forms;
// the sums are exact), of √disc and of Q = |β| + √disc.
void SetUpQuadratic(ConeSetup& cs, const PassFormats& pf) {
  const double u = pf.Ulp();
  double maxU = 0, maxE = 0;
  for (int k = 0; k < 3; ++k) {
    cs.eA += SquareErr(Length(cs.u[k].c), cs.u[k].err, u);
    cs.eDisc += SquareErr(Length(cs.e[k].c), cs.e[k].err, u);
    maxU += cs.u[k].max * cs.u[k].max;
    maxE += cs.e[k].max * cs.e[k].max;
  }
  cs.eA += SquareErr(Length(cs.g.c), cs.g.err, u);
  // Only |q| <= |e| can hit: where the true disc >= 0, or the computed one >= G, |q| is below
  // |e|'s bound (plus the errors), however large q's coefficients (the eye's distance).
  double eNorm = 0, eErr = 0;
  for (int k = 0; k < 3; ++k)
    eNorm += Dot(cs.e[k].c, cs.e[k].c), eErr = std::max(eErr, cs.e[k].err);
  const double qMax = std::min(Length(cs.q.c), std::sqrt(eNorm) + std::sqrt(3.0) * eErr + cs.q.err);
  cs.eDisc += SquareErr(qMax, cs.q.err, u);
  const double maxA = std::max(maxU, cs.g.max * cs.g.max),
               maxDisc = std::max(maxE, cs.q.max * cs.q.max);
  cs.sum3A = Format::Unsigned(IntBitsFor(maxU + u), pf.fracBits);
  cs.sum3Disc = Format::Unsigned(IntBitsFor(maxE + u), pf.fracBits);
  cs.aFormat = Format::Signed(IntBitsFor(maxA + u), pf.fracBits);
  cs.discFormat = Format::Signed(IntBitsFor(maxDisc + u), pf.fracBits);
  cs.rootFormat = Format::Unsigned(IntBitsFor(std::sqrt(maxDisc) + 1), pf.fracBits);
  cs.qFormat = Format::Unsigned(IntBitsFor(cs.beta.max + std::sqrt(maxDisc) + 2), pf.fracBits);
}

// The divisions' target t error in units of e_Q. The threshold D* ≈ 2·tFar·e_Q/target does
// not shrink with the width when the target is a multiple of e_Q, so this factor decides
// how much of a cone the array certifies: 8 left every root with Q < tFar/4 uncertain (the
// showcase's cone: 8.8 % of its pixels); 16 halves that threshold at twice the t error
// (measured with tools/refine-table.sh, docs/simd.md "Refine pass").
constexpr double kConeTargetPerEq = 16;
// The per-PE ladders (ConeLadder) certify every PE at its own error, so the threshold D*
// (rung 0) is set this much lower than the target asks, and the rungs 4^k·D* reach 8× past
// it: a root well inside the cone keeps at most the target's error, and the PEs between
// the new and the old threshold are certified, with their own (larger) margins, instead of
// flagged (docs/simd.md, "Error bounds", cones).
constexpr double kLadderSpan = 8;

// The divisions, aiming at a t error of 64·tFar·2^-F (the planner's nominal order) or
// kConeTargetPerEq × the error of Q, whichever is larger. For C/Q, an in-range root has
// Q >= |C|/tFar, so a threshold below |C|/(1.25·tFar) costs no flags (smaller Q are
// certainly beyond). Then the height s = w·a + t·(d'·a) of each root.
void SetUpDivisions(ConeSetup& cs, const PassFormats& pf, double rho) {
  const double u = pf.Ulp();
  const double target = std::max({64 * cs.tFar * pf.NominalUlp(), kConeTargetPerEq * cs.eQ, 4 * u});
  // The lowest threshold (the widest span) whose quotients still fit t and whose error stays
  // within the cone's radius ρ: a lower D* lets t reach further past tFar, which at low widths
  // can exceed t's range, and a margin wider than the cone ties with whatever lies behind it
  // (it certifies nothing a flag would not).
  for (double span = kLadderSpan;; span /= 2) {
    cs.degenerate = false;
    cs.divA = PlanDivision(cs.eQ, cs.eA, cs.tFar, span * target, 0, pf.fracBits);
    cs.divC = PlanDivision(u / 2, cs.eQ, cs.tFar, span * target, std::abs(cs.C) / (1.25 * cs.tFar),
                           pf.fracBits);
    const ConeDivision* divs[2] = {&cs.divA, &cs.divC};
    for (int i = 0; i < 2; ++i) {
      const ConeDivision& v = *divs[i];
      cs.sFormat[i] =
          Format::Signed(IntBitsFor(std::abs(cs.wa) + 2 * v.tCut * cs.da.max + 1), pf.fracBits);
      if (v.tCut >= std::ldexp(1.0, pf.t.intBits)) cs.degenerate = true;  // a hit would not fit t
    }
    if ((!cs.degenerate && std::max(cs.divA.tError, cs.divC.tError) <= rho) || span <= 1) return;
  }
}

// x rounded up to a multiple of 2^-frac.
double RoundUp(double x, int frac) { return std::ldexp(std::ceil(std::ldexp(x, frac)), -frac); }

// The ladders: at rung (j, k) the error of Q is eβ + eDisc/(2^j·√G) + u, the division's
// error (eN + tRange·eD)/(2^k·D*) + u with eN, eD from that Q (Q/A: eN = e_Q; C/Q: eD = e_Q),
// and the height's s = w·a + t·(d'·a) from it. Rung (0, 0) is the division's tError and eS.
void SetUpLadders(ConeSetup& cs, const PassFormats& pf) {
  const double u = pf.Ulp();
  const ConeDivision* divs[2] = {&cs.divA, &cs.divC};
  for (int i = 0; i < 2; ++i) {
    const ConeDivision& v = *divs[i];
    ConeLadder& l = cs.ladder[i];
    double widest = 0;
    for (int j = 0; j < kDiscRungs; ++j) {
      const double eQ = cs.eQAt[j];
      const double eN = i == 0 ? eQ : v.eN, eD = i == 0 ? v.eD : eQ;
      for (int k = 0; k < kDivRungs; ++k) {
        const double dk = std::ldexp(v.dStar, 2 * k);
        const double e = eN / dk + v.tRange * eD / dk + u;
        l.margin[j][k] = RoundUp(e + u, pf.fracBits);
        l.height[j][k] =
            RoundUp(MulErr(v.tRange, e, Length(cs.da.c), cs.da.err, u) + u / 2 + u, pf.fracBits);
        widest = std::max({widest, l.margin[j][k], l.height[j][k]});
      }
    }
    l.format = Format::Unsigned(IntBitsFor(widest + u), pf.fracBits);
  }
}

ConeSetup MakeConeSetup(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  const Cone& cone = std::get<Cone>(p.shape);
  const double u = pf.Ulp();
  const ObjectFrame fr = MakeObjectFrame(p, eye);
  ConeSetup cs;
  SetUpForms(cs, cone, fr, pf);
  SetUpQuadratic(cs, pf);
  // The grazing band: at least twice the discriminant's error, and (ρ/8)² with ρ the cone's
  // larger radius in world units (as a sphere's (r/8)²), so the root's error e/√G stays small.
  const double spectral = Spectral(p, fr);
  const double rho = std::max(std::abs(cone.baseRadius), std::abs(cone.apexRadius)) / spectral;
  cs.grazeBand = std::max(2 * cs.eDisc, std::pow(rho / 8, 2) * pf.BandScale());
  cs.eRoot = cs.eDisc / std::sqrt(cs.grazeBand) + u;
  cs.eQ = cs.beta.err + cs.eRoot;
  for (int j = 0; j < kDiscRungs; ++j)
    cs.eQAt[j] = cs.beta.err + cs.eDisc / std::ldexp(std::sqrt(cs.grazeBand), j) + u;
  cs.rootsOrdered = cs.grazeBand - cs.eDisc > cs.beta.err * cs.beta.err;
  const ConeReach reach = Reach(p, eye, spectral);
  cs.tFar = reach.far + u;
  cs.tNear = reach.near;
  SetUpDivisions(cs, pf, rho);
  SetUpLadders(cs, pf);
  return cs;
}

Multi Linear(const Multi (&d)[3], const LinearForm& l, int frac) {
  const Fixed c[3] = {Tight(l.c.x, frac), Tight(l.c.y, frac), Tight(l.c.z, frac)};
  return Dot3(d, c, l.format);
}

// One root of the cone: t = ±N/D where |D| >= D* (`sure`), or certainly outside the cone's
// range [tNear, tFar] of t (`beyond`: no hit), or neither (uncertain). See ConeDivision.
struct ConeRoot {
  Multi t, sure, beyond, absD;  // absD: |D|, for the ladder
};

// Certainly |N/D| outside [tNear, tFar] (no point of the cone there), for |N| and |D| with
// errors eN and eD: |N| − eN >= tFar·(|D| + eD), or |N| + eN <= tNear·(|D| − eD). Products
// round down and constants to nearest, which the margins absorb.
Multi Outside(Machine& m, const Multi& absN, const Multi& absD, double eN, double eD, double tNear,
              double tFar, int frac) {
  const double u = std::ldexp(1.0, -frac);
  const Format bf = Format::Unsigned(absD.Format().intBits + IntBitsFor(tFar + u) + 1, frac);
  const Multi far = Add(Mul(absD, Uni{Tight(tFar + u, frac)}, bf),
                        Broadcast(m, Tight(tFar * eD + eN + 3 * u, frac)), bf);
  Multi out = far <= absN;
  if (tNear > 0) {
    const Multi near = Mul(absD, Uni{Tight(std::max(tNear - u, 0.0), frac)}, bf);
    const Format nf = Format::Unsigned(absN.Format().intBits + 1, frac);
    out = out || (Add(absN, Broadcast(m, Tight(tNear * eD + eN + 2 * u, frac)), nf) <= near);
  }
  return out;
}

ConeRoot ConeDivide(Machine& m, const Multi& n, const Multi& den, const Multi& negate,
                    const Multi& active, const ConeDivision& v, double tNear, double tFar,
                    int frac) {
  ConeRoot r;
  const Multi absD = AbsOf(den);
  r.absD = absD;
  r.sure = Broadcast(m, Tight(v.dStar, frac)) <= absD;
  r.beyond = Outside(m, AbsOf(n), absD, v.eN, v.eD, tNear, tFar, frac);
  WithExpectedSaturation(m, [&] {  // a saturated quotient is >= tCut: beyond the cone
    Where(active && r.sure, [&] { r.t = Div(n, den, v.out, kSaturate); });
    Where(negate, [&] { r.t = Neg(r.t, v.out, kSaturate); });
  });
  return r;
}

class ConeProgram final : public ObjectProgram {
 public:
  ConeProgram(const Primitive& p, const Vec3& eye, const PassFormats& pf)
      : pf_(pf), cs_(MakeConeSetup(p, eye, pf)) {
    Bound();
  }

  const ObjectBounds& Bounds() const { return b_; }

  std::vector<PlannedFormat> Formats() const {
    const LinearForm* forms[] = {&cs_.da,   &cs_.g,    &cs_.u[0], &cs_.u[1], &cs_.u[2],
                                 &cs_.e[0], &cs_.e[1], &cs_.e[2], &cs_.q,    &cs_.beta};
    int linear = 1;
    for (const LinearForm* l : forms) linear = std::max(linear, l->format.intBits);
    return {{"linear forms of d", Format::Signed(linear, pf_.fracBits),
             "d'·a, σd'·a, d'⊥, e, d'·(w×a), β (T⁻¹ folded in); the widest of ten"},
            {"|d'⊥|²", cs_.sum3A, "sum of three squares"},
            {"A", cs_.aFormat, "|d'⊥|² − (σd'·a)²"},
            {"|e|²", cs_.sum3Disc, "sum of three squares"},
            {"disc", cs_.discFormat, "|e|² − (d'·(w×a))²"},
            {"root √disc", cs_.rootFormat, "half the discriminant's integer bits"},
            {"Q = |β| + √disc", cs_.qFormat, "sum of the bounds"},
            {"t = Q/A", cs_.divA.out,
             "by division where |A| >= its threshold, else flagged unless beyond"},
            {"t = C/Q", cs_.divC.out,
             "by division where |Q| >= its threshold, else flagged unless beyond"},
            {"height s of Q/A's root", cs_.sFormat[0], "w·a + t·(d'·a)"},
            {"height s of C/Q's root", cs_.sFormat[1], "w·a + t·(d'·a)"},
            {"t", pf_.t, "the nearer valid root"}};
  }

  Candidate Run(Machine& m, const Directions& dirs, Audit* audit) const override;

 private:
  // The bounds: t's error from the divisions (ConeDivision); an object whose quotient could
  // not fit t is always uncertain.
  void Bound() {
    b_.kind = ShapeKind::kCone;
    b_.farthest = cs_.tFar;
    b_.grazeBand = cs_.grazeBand;
    for (const Format& f : {cs_.aFormat, cs_.discFormat, cs_.qFormat, cs_.divA.out, cs_.divC.out,
                            cs_.sFormat[0], cs_.sFormat[1]})
      b_.intBits = std::max(b_.intBits, f.intBits);
    if (cs_.degenerate) {
      b_.alwaysUncertain = true;
      b_.tError = b_.slack = kInf;
      return;
    }
    b_.tError = std::max(cs_.divA.tError, cs_.divC.tError);
    b_.slack = b_.tError + pf_.Ulp();
  }

  Multi UniOf(Machine& m, double x) const { return Broadcast(m, Tight(x, pf_.fracBits)); }

  // Root i's tests: a valid hit (in range, beyond hither, height inside), uncertain (the
  // division undecided, or near hither or a rim, within the PE's margins), and where
  // uncertain the least t a true hit could have.
  void TestRoot(Machine& m, int i, const ConeRoot& r, const Multi& roots, const Multi& da,
                const Multi& hither, const Multi& sLo, const Multi& sHi, const Multi& margin,
                const Multi& height, Multi& valid, Multi& unsure, Multi& low,
                Multi* height_out) const;

  // The audit's record (hosts/simd/audit.h) of the quantities Run computed, with the bounds
  // MakeConeSetup and the ladders claim for them.
  void Record(Audit& audit, const Multi (&d)[3], const Multi& da, const Multi& beta,
              const Multi (&uv)[3], const Multi (&ev)[3], const Multi& aq, const Multi& disc,
              const Multi& root, const Multi& q, const ConeRoot (&rs)[2], const Multi (&margin)[2],
              const Multi (&height)[2], const Multi (&s)[2], const Candidate& out) const;

  // Root i's t and height margins at each PE: the tightest rung of its ladder whose
  // conditions hold (discAt[j − 1]: disc >= 4^j·G).
  void Climb(Machine& m, int i, const Multi (&discAt)[kDiscRungs - 1], const Multi& absD,
             Multi& margin, Multi& height) const;

  PassFormats pf_;
  ConeSetup cs_;
  ObjectBounds b_;
};

void ConeProgram::Climb(Machine& m, int i, const Multi (&discAt)[kDiscRungs - 1], const Multi& absD,
                        Multi& margin, Multi& height) const {
  const ConeLadder& l = cs_.ladder[i];
  const int F = pf_.fracBits;
  const double dStar = (i == 0 ? cs_.divA : cs_.divC).dStar;
  auto at = [&](double x) {
    return Broadcast(
        m, fixed::FromDouble(x, l.format,
                             {fixed::Rounding::kFloor, fixed::OverflowPolicy::kSaturate}));
  };
  Multi divAt[kDivRungs - 1];
  for (int k = 1; k < kDivRungs; ++k)
    divAt[k - 1] = absD >= bitserial::Uni{Tight(RoundUp(std::ldexp(dStar, 2 * k), F), F)};
  margin = at(l.margin[0][0]), height = at(l.height[0][0]);
  // In order of j, then k: the last rung whose conditions hold is the tightest (both grow).
  for (int j = 0; j < kDiscRungs; ++j)
    for (int k = 0; k < kDivRungs; ++k) {
      if (j == 0 && k == 0) continue;
      const Multi cond = j == 0   ? divAt[k - 1]
                         : k == 0 ? discAt[j - 1]
                                  : (discAt[j - 1] && divAt[k - 1]);
      Where(cond, [&] { margin = at(l.margin[j][k]), height = at(l.height[j][k]); });
    }
}

void ConeProgram::TestRoot(Machine& m, int i, const ConeRoot& r, const Multi& roots,
                           const Multi& da, const Multi& hither, const Multi& sLo, const Multi& sHi,
                           const Multi& margin, const Multi& height, Multi& valid, Multi& unsure,
                           Multi& low, Multi* height_out) const {
  const int F = pf_.fracBits;
  const double u = pf_.Ulp();
  const ConeDivision& v = i == 0 ? cs_.divA : cs_.divC;
  const Fixed tMax{pf_.t, pf_.t.MaxRaw()};
  // The height of the hit: s = w·a + t·(d'·a).
  Multi s;
  WithExpectedSaturation(m, [&] {
    s = Add(Mul(r.t, da, cs_.sFormat[i], kSaturate), UniOf(m, cs_.wa), cs_.sFormat[i], kSaturate);
  });
  const Multi inRange = roots && r.sure && (r.t < UniOf(m, v.tCut));
  valid = inRange && (hither < r.t) && (sLo < s) && (s < sHi);
  const Multi notBehind = UniOf(m, pf_.hither - v.tError - u) < r.t;
  const Multi rim = Near(m, r.t - hither, margin, F) || Near(m, s - sLo, height, F) ||
                    Near(m, s - sHi, height, F);
  unsure = (roots && !r.sure && !r.beyond) || (inRange && notBehind && rim);
  // Where uncertain, the true root (if a hit) is >= low.
  WithExpectedSaturation(m, [&] {
    const Multi lowSure = Sub(r.t, margin, pf_.t, kSaturate);
    low = Select(r.sure, lowSure, Select(r.beyond, Broadcast(m, tMax), UniOf(m, cs_.tNear), pf_.t),
                 pf_.t, kSaturate);
  });
  if (height_out) *height_out = std::move(s);  // the audit's (Run's `audit`): not in the pass
}

Candidate ConeProgram::Run(Machine& m, const Directions& dirs, Audit* audit) const {
  const Multi(&d)[3] = dirs.fixed;
  const int F = pf_.fracBits;
  const double u = pf_.Ulp();
  const ConeSetup& cs = cs_;
  auto uni = [&](double x) { return UniOf(m, x); };
  Candidate out;
  const Multi zero = Zero(m);
  if (cs.empty) {  // no height has a non-negative radius
    out.t = Broadcast(m, Fixed{pf_.t, pf_.t.MaxRaw()});
    out.hit = out.uncertain = zero;
    out.tLow = out.t;
    return out;
  }
  // The linear forms of d (uni coefficients with T⁻¹ folded in), then
  // A = |d'⊥|² − (σ d'·a)² and disc = |rw·d'⊥ − σ(d'·a)w⊥|² − (d'·(w × a))².
  const Multi da = Linear(d, cs.da, F), beta = Linear(d, cs.beta, F);
  Multi uv[3], ev[3];
  for (int k = 0; k < 3; ++k) uv[k] = Linear(d, cs.u[k], F), ev[k] = Linear(d, cs.e[k], F);
  const Multi sumU = SumOfSquares(uv, cs.sum3A);
  const Multi aq = Length(cs.g.c) > 0
                       ? Sub(sumU, Square(Linear(d, cs.g, F), cs.aFormat), cs.aFormat)
                       : Convert(sumU, cs.aFormat);
  const Multi disc =
      Sub(SumOfSquares(ev, cs.sum3Disc), Square(Linear(d, cs.q, F), cs.discFormat), cs.discFormat);
  const Multi roots = uni(cs.grazeBand) <= disc;  // certainly two roots (of the infinite cone)
  Multi grazing = Near(m, disc, cs.grazeBand, F);
  const Multi root = Sqrt(disc, cs.rootFormat);
  // Q = |β| + √disc; t = −sgn(β)·Q/A and −sgn(β)·C/Q (the stable pair).
  const Multi q = Add(AbsOf(beta), root, cs.qFormat);
  const Multi negate = zero <= beta;
  const ConeRoot rs[2] = {
      ConeDivide(m, q, aq, negate, roots, cs.divA, cs.tNear, cs.tFar, F),
      ConeDivide(m, uni(cs.C), q, negate, roots, cs.divC, cs.tNear, cs.tFar, F)};
  // A grazing ray matters only if the double root could lie in [tNear, tFar]: there Q is
  // within eβ + √(G + e_disc) of its true value (both roots of the true disc >= 0 are).
  {
    const double eQg = cs.beta.err + std::sqrt(cs.grazeBand + cs.eDisc) + u;
    const Multi absQ = AbsOf(q), absC = AbsOf(uni(cs.C));
    grazing = grazing && !(Outside(m, absQ, AbsOf(aq), eQg, cs.eA, cs.tNear, cs.tFar, F) &&
                           Outside(m, absC, absQ, u / 2, eQg, cs.tNear, cs.tFar, F));
  }
  const Multi hither = uni(pf_.hither), sLo = uni(cs.sLo), sHi = uni(cs.sHi);
  Multi discAt[kDiscRungs - 1];
  for (int j = 1; j < kDiscRungs; ++j)
    discAt[j - 1] = disc >= bitserial::Uni{Tight(RoundUp(std::ldexp(cs.grazeBand, 2 * j), F), F)};
  Multi valid[2], unsure[2], low[2], margin[2], height[2], s[2];
  for (int i = 0; i < 2; ++i) {
    Climb(m, i, discAt, rs[i].absD, margin[i], height[i]);
    TestRoot(m, i, rs[i], roots, da, hither, sLo, sHi, margin[i], height[i], valid[i], unsure[i],
             low[i], audit ? &s[i] : nullptr);
  }
  out.hit = valid[0] || valid[1];
  const Multi first = valid[0] && (!valid[1] || rs[0].t < rs[1].t);
  WithExpectedSaturation(m, [&] { out.t = Select(first, rs[0].t, rs[1].t, pf_.t, kSaturate); });
  const Format marginFormat =
      Format::Unsigned(std::max(cs.ladder[0].format.intBits, cs.ladder[1].format.intBits), F);
  if (!b_.alwaysUncertain) out.lowMargin = Select(first, margin[0], margin[1], marginFormat);
  // The exact roots paired with Q/A and C/Q multiply to C/A; with β's computed sign right,
  // |Q/A| >= |C/Q| (Q² >= β² >= AC where AC > 0; Q² >= disc >= −AC where AC < 0); with it
  // wrong (|β| <= eβ) the roots have opposite signs, as disc >= G − e_disc > eβ² >= β²
  // (cs.rootsOrdered). Either way, where C/Q is a certain valid hit, Q/A is behind the eye or
  // no nearer, so its own doubts (an undecided division seen along the axis, its rims) do
  // not matter.
  out.uncertain = grazing || unsure[1] || (cs.rootsOrdered ? unsure[0] && !valid[1] : unsure[0]);
  out.tLow = Select(grazing, uni(cs.tNear), Min(low[0], low[1], pf_.t), pf_.t);
  if (b_.alwaysUncertain) {  // the bounds do not close: every PE that may hit is flagged
    out.uncertain = uni(-cs.grazeBand) < disc;
    out.tLow = Convert(uni(cs.tNear), pf_.t);
  }
  if (audit) Record(*audit, d, da, beta, uv, ev, aq, disc, root, q, rs, margin, height, s, out);
  return out;
}

// Where each bound is claimed: a linear form, A and its own error everywhere; the
// discriminant where its computed value is >= −G; √disc and Q = |β| + √disc at rung j of the
// discriminant's ladder (computed disc >= 4^j·G, as the ladder's conditions round it); a root's
// quotient and its height within the PE's ladder margins where the root is certainly a root
// (disc >= G), its divisor is at least D* and it lies between hither − tError and tCut (where
// TestRoot relies on them: a quotient far behind the eye may saturate); a certain hit's t
// within its lowMargin and within the object's tError. Nothing where the bounds do not close.
void ConeProgram::Record(Audit& audit, const Multi (&d)[3], const Multi& da, const Multi& beta,
                         const Multi (&uv)[3], const Multi (&ev)[3], const Multi& aq,
                         const Multi& disc, const Multi& root, const Multi& q,
                         const ConeRoot (&rs)[2], const Multi (&margin)[2],
                         const Multi (&height)[2], const Multi (&s)[2],
                         const Candidate& out) const {
  const ConeSetup& cs = cs_;
  if (b_.alwaysUncertain || cs.empty) return;
  const int F = pf_.fracBits;
  const double u = pf_.Ulp();
  const int64_t n = disc.GetMachine().VirtualPes();
  const auto everywhere = [&](double b) { return Audit::Where({}, b, n); };
  const auto tight = [&](double x) { return fixed::ToDouble(Tight(x, F)); };
  audit.Record("d'·a", da, everywhere(cs.da.err));
  audit.Record("σd'·a", Linear(d, cs.g, F), everywhere(cs.g.err));
  audit.Record("β", beta, everywhere(cs.beta.err));
  for (int k = 0; k < 3; ++k) {
    audit.Record(std::string("d'⊥") + "xyz"[k], uv[k], everywhere(cs.u[k].err));
    audit.Record(std::string("e") + "xyz"[k], ev[k], everywhere(cs.e[k].err));
  }
  audit.Record("d'·(w×a)", Linear(d, cs.q, F), everywhere(cs.q.err));
  audit.Record("A", aq, everywhere(cs.eA));
  const std::vector<double> dv = Audit::Values(disc);
  std::vector<double> eDisc(n, Audit::kNoClaim), eRoot(n, Audit::kNoClaim), eQ(n, Audit::kNoClaim);
  for (int64_t pe = 0; pe < n; ++pe) {
    if (dv[pe] >= -tight(cs.grazeBand)) eDisc[pe] = cs.eDisc;
    for (int j = 0; j < kDiscRungs; ++j)
      if (dv[pe] >=
          (j == 0 ? tight(cs.grazeBand) : tight(RoundUp(std::ldexp(cs.grazeBand, 2 * j), F)))) {
        eQ[pe] = cs.eQAt[j], eRoot[pe] = cs.eQAt[j] - cs.beta.err;  // the ladder's, less β's
      }
  }
  audit.Record("disc", disc, eDisc);
  audit.Record("root", root, eRoot);
  audit.Record("Q", q, eQ);
  const ConeDivision* divs[2] = {&cs.divA, &cs.divC};
  const char* names[2] = {"Q/A", "C/Q"};
  for (int i = 0; i < 2; ++i) {
    const std::vector<double> t = Audit::Values(rs[i].t), absD = Audit::Values(rs[i].absD),
                              mt = Audit::Values(margin[i]), ms = Audit::Values(height[i]);
    std::vector<double> eT(n, Audit::kNoClaim), eS(n, Audit::kNoClaim);
    for (int64_t pe = 0; pe < n; ++pe)
      if (dv[pe] >= tight(cs.grazeBand) && absD[pe] >= tight(divs[i]->dStar) &&
          t[pe] < tight(divs[i]->tCut) &&
          t[pe] > tight(pf_.hither - divs[i]->tError - u))  // TestRoot's inRange && notBehind
        eT[pe] = mt[pe], eS[pe] = ms[pe];
    audit.Record(std::string("t ") + names[i], rs[i].t, eT);
    audit.Record(std::string("s ") + names[i], s[i], eS);
    audit.Record(std::string("|D| ") + names[i], rs[i].absD,
                 std::vector<double>(n, Audit::kNoClaim));
  }
  const std::vector<double> hit = Audit::Values(out.hit), unsure = Audit::Values(out.uncertain),
                            lm = Audit::Values(out.lowMargin);
  std::vector<double> eT(n, Audit::kNoClaim), eObject(n, Audit::kNoClaim);
  for (int64_t pe = 0; pe < n; ++pe)
    if (hit[pe] && !unsure[pe]) eT[pe] = lm[pe], eObject[pe] = b_.tError;
  audit.Record("t (lowMargin)", out.t, eT);
  audit.Record("t", out.t, eObject);
  audit.constants = {{"grazeBand", cs.grazeBand},
                     {"dStar Q/A", cs.divA.dStar},
                     {"dStar C/Q", cs.divC.dStar},
                     {"tCut Q/A", cs.divA.tCut},
                     {"tCut C/Q", cs.divC.tCut},
                     {"tNear", cs.tNear},
                     {"tFar", cs.tFar},
                     {"C", cs.C},
                     {"tError", b_.tError}};
}

}  // namespace

ObjectExtent ConeExtent(const Primitive& p, const Vec3& eye) {
  // The planner's range probe: the bounding sphere's far side plus 2^-16 (the margin the
  // cone's tFar adds at 16 fraction bits).
  const Cone& cone = std::get<Cone>(p.shape);
  ObjectExtent e;
  e.farthest = Reach(p, eye, Spectral(p, MakeObjectFrame(p, eye))).far + std::ldexp(1.0, -16);
  // Half the larger radius, or half the height, in world units (r / ‖T⁻¹‖_F).
  e.feature = std::min(std::max(std::abs(cone.baseRadius), std::abs(cone.apexRadius)),
                       Length(cone.apex - cone.base)) /
              2 / InverseFrobenius(p);
  return e;
}

ObjectPlan PlanCone(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  return PlanOf<ConeProgram>(p, eye, pf);
}

}  // namespace zephyr::simd
