// hosts/simd/shapes.cpp — the per-primitive array programs of the SIMD primary pass and the
// host-side error analysis that makes their uncertain-pixel flags sound (docs/simd.md).
#include "hosts/simd/shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "fixed/check.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;

double PassFormats::Ulp() const { return std::ldexp(1.0, -fracBits); }
double PassFormats::DirError() const { return std::ldexp(0.5, -dirFracBits); }

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int IntBitsFor(double bound) {
  return std::max(1, bound <= 1 ? 1 : int(std::ceil(std::log2(bound + 1))));
}

// A uni constant rounded to nearest in the narrowest format with F fraction bits (a multiply
// by a uni costs one row per one bit).
Fixed Tight(double x, int frac) {
  return fixed::FromDouble(x, Format::Signed(IntBitsFor(std::abs(x)), frac),
                           {fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate});
}

// The error of a floor-rounded product x·y when |x| <= mx with error ex and |y| <= my with
// error ey (u: the result's ulp).
double MulErr(double mx, double ex, double my, double ey, double u) {
  return mx * ey + my * ex + ex * ey + u;
}

const fixed::Policy kSaturate{fixed::Rounding::Floor, fixed::OverflowPolicy::Saturate};

// The object's linear inverse (world -> object) rows, object-space eye, and ‖T_lin‖_F.
struct ObjectFrame {
  double a[3][3];
  Vec3 eye;
  double forwardNorm = 1;  // ‖T's linear part‖_F (>= σ_max of T, so σ_min(T⁻¹) >= 1/this)
  double rowSum[3] = {};   // Σ_j |T⁻¹_kj|: |d'_k| <= this for |d_j| <= 1
  double ddMax = 0;        // Σ_k rowSum_k² >= |d'|²: the formats of d' and |d'|²
};

ObjectFrame Frame(const Primitive& p, const Vec3& eye) {
  ObjectFrame f;
  const Affine t = p.transform ? *p.transform : Affine{};
  const Affine inv = t.Inverse();
  double fn = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      f.a[i][j] = inv.m[i][j];
      fn += t.m[i][j] * t.m[i][j];
      f.rowSum[i] += std::abs(inv.m[i][j]);
    }
    f.ddMax += f.rowSum[i] * f.rowSum[i];
  }
  f.forwardNorm = std::sqrt(fn);
  f.eye = inv.ApplyPoint(eye);
  return f;
}

// A polygon in world space (an affine map keeps it planar, so T⁻¹ folds into the host's
// constants: g·(T⁻¹d) = (T⁻ᵀg)·d), its unit normal and the eye's signed distance.
struct WorldPolygon {
  std::vector<Vec3> v;
  Vec3 normal;
  double eyeDistance = 0;  // n̂·(v0 − eye)
  bool convex = true;
  // Edge groups: inside a group iff every edge function is > 0 (oriented on the host);
  // a convex polygon is one group, a concave one a fan of triangles (even-odd = parity).
  std::vector<std::vector<Vec3>> groups;  // unit edge normals ĝ per group
  bool degenerate = false;
};

WorldPolygon MakeWorldPolygon(const Primitive& p, const Vec3& eye) {
  WorldPolygon w;
  for (const Vec3& v : std::get<Polygon>(p.shape).vertices)
    w.v.push_back(p.transform ? p.transform->ApplyPoint(v) : v);
  const size_t n = w.v.size();
  Vec3 nn;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 &a = w.v[i], &b = w.v[(i + 1) % n];
    nn += Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
  }
  w.normal = Normalize(nn);
  w.eyeDistance = Dot(w.normal, w.v[0] - eye);
  const double sigma = w.eyeDistance >= 0 ? 1 : -1;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 e0 = w.v[(i + 1) % n] - w.v[i], e1 = w.v[(i + 2) % n] - w.v[(i + 1) % n];
    if (Dot(Cross(e0, e1), w.normal) < 0) w.convex = false;
  }
  // ĝ = σ·τ·normalize((a − eye) × (b − eye)): for a ray in front of the eye through the
  // group's inside, every ĝ·d > 0 (τ: the group's winding against the polygon's normal).
  auto edge = [&](const Vec3& a, const Vec3& b, double tau) {
    const Vec3 g = Cross(a - eye, b - eye);
    const double len = Length(g);
    if (!(len > 1e-300)) {
      w.degenerate = true;
      return Vec3{};
    }
    return g * (sigma * tau / len);
  };
  if (w.convex) {
    std::vector<Vec3> g;
    for (size_t i = 0; i < n; ++i) g.push_back(edge(w.v[i], w.v[(i + 1) % n], 1));
    w.groups.push_back(g);
  } else {
    for (size_t i = 1; i + 1 < n; ++i) {
      const Vec3 area = Cross(w.v[i] - w.v[0], w.v[i + 1] - w.v[0]);
      const double tau = Dot(area, w.normal);
      if (tau == 0) continue;  // a collinear fan triangle covers nothing
      const double s = tau > 0 ? 1 : -1;
      w.groups.push_back({edge(w.v[0], w.v[i], s), edge(w.v[i], w.v[i + 1], s), edge(w.v[i + 1], w.v[0], s)});
    }
  }
  if (w.groups.empty()) w.degenerate = true;
  return w;
}

// The grazing band G of a discriminant r2 − Σ_k c_k² (three clamped cross components, each
// with error eCross; r2's own error eR2) and the discriminant's error bound in the region
// that matters. A pixel whose computed disc is <= −G is a certain miss, one >= G a certain
// hit whose root is within eDisc/√G; in between it is grazing. In that region Σ c² <=
// r2 + G, so |c| <= √(r2 + G) + eCross (below the clamp's range `clampRange`, or saturation
// only moves c towards the boundary), which bounds the squares' error. G >= 2·eDisc, and at
// least `floorBand`; found by iterating G (it only grows).
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

// One linear form c·d of the direction with uni coefficients c (rounded to nearest): the
// computed value is within `err` of the exact c·d̂ along the exact unit direction, and
// |value| <= max.
struct LinearForm {
  Vec3 c;
  double max = 0, err = 0;
  Format format;
};

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

// The error of a floor-rounded square x² when |x| <= m exactly and x has error e.
double SquareErr(double m, double e, double u) { return 2 * m * e + e * e + u; }

// One division t = N/D of the cone program, decided per PE against a threshold D* on |D|
// (docs/simd.md, "Error bounds", cone). With |N − N_exact| <= eN and |D − D_exact| <= eD:
//  - |D| >= D*: |t − t_exact| <= (eN + |t_exact|·eD)/|D| <= eps + |t_exact|·eta (eta =
//    eD/D*, eps = eN/D*). A computed |t| >= tCut means |t_exact| >= tFar (no point of the
//    cone is that far: the root is not a hit); below it |t_exact| <= tRange and the error is
//    at most tError.
//  - |D| < D*: the root is no hit when certainly outside [tNear, tFar] (Outside); else the
//    PE is uncertain.
struct ConeDivision {
  double eN = 0, eD = 0, dStar = 0, tCut = 0, tRange = 0, tError = 0;
  Format out;  // the quotient (holds 2·tCut; saturation means "beyond")
};

ConeDivision PlanDivision(double eN, double eD, double tFar, double target, double freeThreshold, int frac) {
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
  bool empty = false;      // no height has a non-negative radius: never hit
  Format aFormat, discFormat, sum3A, sum3Disc, rootFormat, qFormat;
  double eA = 0, eDisc = 0, grazeBand = 0, eRoot = 0, eQ = 0;
  ConeDivision divA, divC;  // t = Q/A and t = C/Q
  double eS[2] = {};        // height error for each division's root
  Format sFormat[2];
  double tFar = 0, tNear = 0;
  bool degenerate = false;  // the bounds do not close at these widths: always uncertain
};

ConeSetup MakeConeSetup(const Primitive& p, const Vec3& eye, const PassFormats& pf) {
  const Cone& cone = std::get<Cone>(p.shape);
  const double u = pf.Ulp();
  const ObjectFrame fr = Frame(p, eye);
  ConeSetup cs;
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
  // A = Σu² − g², disc = Σe² − q² (squares of computed forms; the sums are exact).
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
  for (int k = 0; k < 3; ++k) eNorm += Dot(cs.e[k].c, cs.e[k].c), eErr = std::max(eErr, cs.e[k].err);
  const double qMax = std::min(Length(cs.q.c), std::sqrt(eNorm) + std::sqrt(3.0) * eErr + cs.q.err);
  cs.eDisc += SquareErr(qMax, cs.q.err, u);
  const double maxA = std::max(maxU, cs.g.max * cs.g.max), maxDisc = std::max(maxE, cs.q.max * cs.q.max);
  cs.sum3A = Format::Unsigned(IntBitsFor(maxU + u), pf.fracBits);
  cs.sum3Disc = Format::Unsigned(IntBitsFor(maxE + u), pf.fracBits);
  cs.aFormat = Format::Signed(IntBitsFor(maxA + u), pf.fracBits);
  cs.discFormat = Format::Signed(IntBitsFor(maxDisc + u), pf.fracBits);
  cs.rootFormat = Format::Unsigned(IntBitsFor(std::sqrt(maxDisc) + 1), pf.fracBits);
  cs.qFormat = Format::Unsigned(IntBitsFor(cs.beta.max + std::sqrt(maxDisc) + 2), pf.fracBits);
  // The grazing band: at least twice the discriminant's error, and (ρ/8)² with ρ the cone's
  // larger radius in world units (as a sphere's (r/8)²), so the root's error e/√G stays small.
  // ‖T‖₂ <= √(‖T‖₁‖T‖∞) (tighter than the Frobenius norm for rotations and scales).
  double spectral = 1;
  if (p.transform) {
    double n1 = 0, nInf = 0;
    for (int i = 0; i < 3; ++i) {
      double row = 0, col = 0;
      for (int j = 0; j < 3; ++j) row += std::abs(p.transform->m[i][j]), col += std::abs(p.transform->m[j][i]);
      nInf = std::max(nInf, row), n1 = std::max(n1, col);
    }
    spectral = std::min(fr.forwardNorm, std::sqrt(n1 * nInf));
  }
  const double rho = std::max(std::abs(cone.baseRadius), std::abs(cone.apexRadius)) / spectral;
  cs.grazeBand = std::max(2 * cs.eDisc, std::pow(rho / 8, 2));
  cs.eRoot = cs.eDisc / std::sqrt(cs.grazeBand) + u;
  cs.eQ = cs.beta.err + cs.eRoot;
  // World-space bounding sphere of the cone: every hit has tNear <= t <= tFar.
  const double halfH = h / 2, rMax = std::max(std::abs(cone.baseRadius), std::abs(cone.apexRadius));
  const Vec3 mid = cone.base + a * halfH;
  const Vec3 midWorld = p.transform ? p.transform->ApplyPoint(mid) : mid;
  const double reach = std::sqrt(halfH * halfH + rMax * rMax) * spectral;
  cs.tFar = (Length(midWorld - eye) + reach) * (1 + 1e-12) + u;
  cs.tNear = std::max(0.0, Length(midWorld - eye) - reach);
  // Divisions, aiming at a t error of 64·tFar·2^-F (the planner's nominal order) or 8× the
  // error of Q, whichever is larger. For C/Q, an in-range root has Q >= |C|/tFar, so a
  // threshold below |C|/(1.25·tFar) costs no flags (smaller Q are certainly beyond).
  const double target = std::max({64 * cs.tFar * u, 8 * cs.eQ, 4 * u});
  cs.divA = PlanDivision(cs.eQ, cs.eA, cs.tFar, target, 0, pf.fracBits);
  cs.divC = PlanDivision(u / 2, cs.eQ, cs.tFar, target, std::abs(cs.C) / (1.25 * cs.tFar), pf.fracBits);
  const ConeDivision* divs[2] = {&cs.divA, &cs.divC};
  for (int i = 0; i < 2; ++i) {
    const ConeDivision& v = *divs[i];
    cs.eS[i] = MulErr(v.tRange, v.tError, Length(cDa), cs.da.err, u) + u / 2;
    cs.sFormat[i] = Format::Signed(IntBitsFor(std::abs(cs.wa) + 2 * v.tCut * cs.da.max + 1), pf.fracBits);
    if (v.tCut >= std::ldexp(1.0, pf.t.intBits)) cs.degenerate = true;  // a hit would not fit t
  }
  return cs;
}

}  // namespace

ObjectBounds BoundObject(const Scene& scene, int index, const PassFormats& pf) {
  const Primitive& p = scene.objects[index];
  const Vec3 eye = scene.camera.from;
  const double u = pf.Ulp(), dd = pf.DirError();
  ObjectBounds b;
  b.kind = p.Kind();
  b.transformed = bool(p.transform);
  if (b.kind == ShapeKind::kSphere && !p.transform) {
    // Hearn–Baker through the cross product (docs/simd.md, "Error bounds").
    const Sphere& s = std::get<Sphere>(p.shape);
    const Vec3 f = s.center - eye;
    double eTca = 0, eCross = 0;
    for (int k = 0; k < 3; ++k) {
      eTca += MulErr(1, dd, std::abs(f[k]), u / 2, u);
      eCross = std::max(eCross, MulErr(1, dd, std::abs(f[(k + 1) % 3]), u / 2, u) +
                                    MulErr(1, dd, std::abs(f[(k + 2) % 3]), u / 2, u));
    }
    const auto [band, eDisc] = GrazingBand(s.radius * s.radius, std::pow(s.radius / 8, 2), eCross,
                                           u / 2, std::ldexp(1.0, IntBitsFor(s.radius)), u);
    b.grazeBand = band;
    b.tError = eTca + eDisc / std::sqrt(b.grazeBand) + u;
    b.slack = std::max(b.tError, eTca + std::sqrt(b.grazeBand + eDisc)) + u;
    b.farthest = Length(f) + s.radius;
    b.intBits = IntBitsFor(b.farthest) + 1;
    return b;
  }
  if (b.kind == ShapeKind::kSphere) {
    // An ellipsoid: the unit-sphere test in object space with d' = T⁻¹d (not unit).
    const Sphere& s = std::get<Sphere>(p.shape);
    const ObjectFrame fr = Frame(p, eye);
    const Vec3 f = s.center - fr.eye;
    double eDp[3], mDp[3];
    for (int k = 0; k < 3; ++k) {
      eDp[k] = 0;
      for (int j = 0; j < 3; ++j) eDp[k] += MulErr(1, dd, std::abs(fr.a[k][j]), u / 2, u);
      mDp[k] = fr.rowSum[k] + eDp[k];
    }
    double eTcaN = 0, eCross = 0, eDd = 0;
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      eTcaN += MulErr(mDp[k], eDp[k], std::abs(f[k]), u / 2, u);
      eCross = std::max(eCross, MulErr(mDp[j], eDp[j], std::abs(f[i]), u / 2, u) +
                                    MulErr(mDp[i], eDp[i], std::abs(f[j]), u / 2, u));
      eDd += 2 * mDp[k] * eDp[k] + eDp[k] * eDp[k] + u;
    }
    const double ddMax = fr.ddMax + eDd;
    const double ddMin = std::pow((1 - std::sqrt(3.0) * dd) / fr.forwardNorm, 2) - eDd;
    const double eR2dd = s.radius * s.radius * eDd + ddMax * u / 2 + u;
    const auto [band, eDisc] =
        GrazingBand(s.radius * s.radius * ddMax, std::pow(s.radius * std::sqrt(std::max(ddMin, 0.0)) / 8, 2),
                    eCross, eR2dd, std::ldexp(1.0, IntBitsFor(s.radius * std::sqrt(fr.ddMax))), u);
    const Vec3 centre = p.transform->ApplyPoint(s.center);
    b.farthest = Length(centre - eye) + s.radius * fr.forwardNorm;
    b.intBits = IntBitsFor(std::max(b.farthest, (Length(f) + s.radius) * std::sqrt(ddMax)) + 1) + 1;
    if (!(ddMin > 0)) {
      b.alwaysUncertain = true;
      b.tError = b.slack = kInf;
      return b;
    }
    b.grazeBand = band;
    const double eNum = eTcaN + eDisc / std::sqrt(b.grazeBand) + u;
    b.tError = eNum / ddMin + b.farthest * eDd / ddMin + u;
    b.slack = b.tError + 2 * std::sqrt(b.grazeBand + eDisc) / ddMin + u;
    return b;
  }
  if (b.kind == ShapeKind::kPolygon) {
    const WorldPolygon w = MakeWorldPolygon(p, eye);
    for (const Vec3& v : w.v) b.farthest = std::max(b.farthest, Length(v - eye));
    b.intBits = IntBitsFor(b.farthest) + 1;
    // ĝ·d and n̂·d: unit constants (rounded to nearest) times d.
    const double eE = std::sqrt(3.0) * dd + 1.5 * u * (1 + dd) + 3 * u;
    b.grazeBand = eE;
    const double n = std::abs(w.eyeDistance);
    const double denMin = n / b.farthest - eE;
    if (w.degenerate || !(denMin > 0)) {
      b.alwaysUncertain = true;
      b.tError = b.slack = kInf;
      return b;
    }
    b.tError = b.farthest * eE / denMin + (u / 2) / denMin + u;
    b.slack = b.tError + u;
    return b;
  }
  // A cone or cylinder (NFF `c`), through T⁻¹ folded into linear forms of d.
  const ConeSetup cs = MakeConeSetup(p, eye, pf);
  b.farthest = cs.tFar;
  b.grazeBand = cs.grazeBand;
  for (const Format& f : {cs.aFormat, cs.discFormat, cs.qFormat, cs.divA.out, cs.divC.out, cs.sFormat[0], cs.sFormat[1]})
    b.intBits = std::max(b.intBits, f.intBits);
  if (cs.degenerate) {
    b.alwaysUncertain = true;
    b.tError = b.slack = kInf;
    return b;
  }
  b.tError = std::max(cs.divA.tError, cs.divC.tError);
  b.slack = b.tError + pf.Ulp();
  return b;
}

namespace {

Multi Dot3(const Multi (&d)[3], const Fixed (&c)[3], Format out) {
  return Add(Add(Mul(d[0], Uni{c[0]}, out), Mul(d[1], Uni{c[1]}, out), out), Mul(d[2], Uni{c[2]}, out), out);
}

Multi Zero(Machine& m) { return Broadcast(m, Fixed{Format::Unsigned(1, 0), 0}); }

// |x| < band (band a host constant), with the clamp's saturation expected.
Multi Near(Machine& m, const Multi& x, double band, int frac) {
  Multi a;
  WithExpectedSaturation(m, [&] {
    a = Abs(x, Format::Unsigned(std::max(1, x.Format().intBits), frac), kSaturate);
  });
  return a < Broadcast(m, Tight(band, frac));
}

// x − c, saturating at the format's ends (a bound, not a value that must be exact).
Multi SubBound(Machine& m, const Multi& x, double c, Format out) {
  if (!std::isfinite(c)) return Broadcast(m, Fixed{out, out.MinRaw()});
  Multi r;
  WithExpectedSaturation(m, [&] { r = Sub(x, Broadcast(m, Tight(c, out.fracBits)), out, kSaturate); });
  return r;
}

// |f × d|² with each cross component (format `cross`) clamped to `clamped` first: only a
// component below the radius can hit, so saturation there means a miss, not an error.
Multi CrossSquared(Machine& m, const Multi (&d)[3], const Fixed (&f)[3], Format cross, Format clamped,
                   Format square) {
  const Multi c[3] = {Sub(Mul(d[2], Uni{f[1]}, cross), Mul(d[1], Uni{f[2]}, cross), cross),
                      Sub(Mul(d[0], Uni{f[2]}, cross), Mul(d[2], Uni{f[0]}, cross), cross),
                      Sub(Mul(d[1], Uni{f[0]}, cross), Mul(d[0], Uni{f[1]}, cross), cross)};
  Multi sum;
  WithExpectedSaturation(m, [&] {
    Multi sq[3];
    for (int k = 0; k < 3; ++k) sq[k] = Square(Convert(c[k], clamped, kSaturate), square, kSaturate);
    sum = Add(Add(sq[0], sq[1], square, kSaturate), sq[2], square, kSaturate);
  });
  return sum;
}

Candidate TestSphere(Machine& m, const Sphere& s, const Vec3& eye, const Multi (&d)[3],
                     const PassFormats& pf, const ObjectBounds& b) {
  const int F = pf.fracBits;
  const Format T = pf.t, L = pf.t;
  const int R = IntBitsFor(s.radius);
  const Format clamped = Format::Signed(R, F), square = Format::Unsigned(2 * R + 2, F),
               discF = Format::Signed(2 * R + 2, F), rootF = Format::Unsigned(R + 1, F);
  const Vec3 fd = s.center - eye;  // eye to centre: a uni
  const Fixed f[3] = {Tight(fd.x, F), Tight(fd.y, F), Tight(fd.z, F)};
  // tca = f·d, the distance along the ray to the closest approach.
  const Multi tca = Dot3(d, f, L);
  // Hearn–Baker: |f − (f·d)d| = |f × d| for unit d; only |f×d| <= r can hit, so each
  // component is clamped to r's integer bits (saturation there means a miss, not an error).
  const Multi sum = CrossSquared(m, d, f, L, clamped, square);
  const Multi disc = Sub(Broadcast(m, Tight(s.radius * s.radius, F)), sum, discF);
  const Multi root = Sqrt(disc, rootF);
  const Multi t0 = Sub(tca, root, T), t1 = Add(tca, root, T);
  const Multi hither = Broadcast(m, Tight(pf.hither, F));
  Candidate out;
  out.t = Select(hither < t0, t0, t1, T);  // the far root when the eye is inside
  out.hit = (Zero(m) <= disc) && (hither < out.t);
  // Uncertain: the discriminant within its bound of zero, or the near root within its
  // bound of hither — and the far root not certainly behind the eye.
  const Multi front = Broadcast(m, Tight(pf.hither - b.slack, F)) < t1;
  out.uncertain = (Near(m, disc, b.grazeBand, F) || Near(m, t0 - hither, b.tError + pf.Ulp(), F)) && front;
  out.tLow = SubBound(m, t0, b.slack, T);
  return out;
}

Candidate TestEllipsoid(Machine& m, const Primitive& p, const Vec3& eye, const Multi (&d)[3],
                        const PassFormats& pf, const ObjectBounds& b) {
  const int F = pf.fracBits;
  const Sphere& s = std::get<Sphere>(p.shape);
  const ObjectFrame fr = Frame(p, eye);
  const Vec3 fv = s.center - fr.eye;  // object space: a uni
  const Fixed f[3] = {Tight(fv.x, F), Tight(fv.y, F), Tight(fv.z, F)};
  // d' = T⁻¹'s 3×3 times d: nine multiplies by uni constants.
  Multi dp[3];
  for (int k = 0; k < 3; ++k) {
    const Fixed a[3] = {Tight(fr.a[k][0], F), Tight(fr.a[k][1], F), Tight(fr.a[k][2], F)};
    dp[k] = Dot3(d, a, Format::Signed(IntBitsFor(fr.rowSum[k] + pf.Ulp() * 4), F));
  }
  const double ddMax = fr.ddMax, rd = s.radius * std::sqrt(ddMax);
  const int R = IntBitsFor(rd);
  const Format N = Format::Signed(b.intBits, F);
  const Format clamped = Format::Signed(R, F), square = Format::Unsigned(2 * R + 2, F),
               discF = Format::Signed(2 * R + 2, F), rootF = Format::Unsigned(R + 1, F),
               ddF = Format::Unsigned(IntBitsFor(ddMax + 1), F);
  // tcaN = f·d' = tca·|d'|², cross = f × d', dd = |d'|²; disc = r²|d'|² − |f × d'|²
  // = |d'|²·(r² − |v|²) with v the closest-approach vector (Hearn–Baker, d' not unit).
  const Multi tcaN = Dot3(dp, f, N);
  const Multi sum = CrossSquared(m, dp, f, N, clamped, square);
  const Multi dd = Add(Add(Square(dp[0], ddF), Square(dp[1], ddF), ddF), Square(dp[2], ddF), ddF);
  const Multi r2dd = Mul(dd, Uni{Tight(s.radius * s.radius, F)}, square);
  const Multi disc = Sub(r2dd, sum, discF);
  const Multi root = Sqrt(disc, rootF);
  const Format numF = Format::Signed(b.intBits + 1, F);
  const Multi num0 = Sub(tcaN, root, numF), num1 = Add(tcaN, root, numF);
  const Multi hd = pf.hither > 0 ? Mul(dd, Uni{Tight(pf.hither, F)}, numF) : Broadcast(m, Fixed{numF, 0});
  const Multi num = Select(hd < num0, num0, num1, numF);
  Candidate out;
  out.hit = (Zero(m) <= disc) && (hd < num);
  out.uncertain = b.alwaysUncertain ? (Zero(m) <= num1) : Near(m, disc, b.grazeBand, F) ||
                  Near(m, num0 - hd, b.tError * ddMax + pf.Ulp(), F);
  const Multi numPos = Max(num, Zero(m), numF);
  Where(out.hit || out.uncertain, [&] { out.t = Div(numPos, dd, pf.t, kSaturate); });
  out.tLow = SubBound(m, out.t, b.slack, pf.t);
  return out;
}

Candidate TestPolygon(Machine& m, const Primitive& p, const Vec3& eye, const Multi (&d)[3],
                      const PassFormats& pf, const ObjectBounds& b) {
  const int F = pf.fracBits;
  const WorldPolygon w = MakeWorldPolygon(p, eye);
  const Format unit = Format::Signed(1, F);
  auto constants = [&](const Vec3& v) {
    return std::array<Fixed, 3>{Tight(v.x, F), Tight(v.y, F), Tight(v.z, F)};
  };
  // Inside: parity over the groups of (every edge function ĝ·d > 0); each edge function is
  // a linear form in d with uni coefficients. Uncertain: some group neither clearly inside
  // (all > band) nor clearly outside (one < −band).
  const Multi band = Broadcast(m, Tight(b.grazeBand, F)), zero = Zero(m);
  const Multi negBand = Broadcast(m, fixed::Neg(Tight(b.grazeBand, F), Format::Signed(1, F)));
  Multi inside, edgeUncertain;
  for (const std::vector<Vec3>& group : w.groups) {
    Multi in, clearIn, clearOut;
    for (const Vec3& g : group) {
      const auto c = constants(g);
      const Fixed cc[3] = {c[0], c[1], c[2]};
      const Multi e = Dot3(d, cc, unit);
      Multi pos = zero < e, posClear = band < e, negClear = e < negBand;
      in = in.Empty() ? pos : (in && pos);
      clearIn = clearIn.Empty() ? posClear : (clearIn && posClear);
      clearOut = clearOut.Empty() ? negClear : (clearOut || negClear);
    }
    const Multi unsure = !(clearIn || clearOut);
    inside = inside.Empty() ? in : Xor(inside, in);
    edgeUncertain = edgeUncertain.Empty() ? unsure : (edgeUncertain || unsure);
  }
  if (w.groups.empty()) inside = zero, edgeUncertain = !zero;  // degenerate: always flagged
  // The plane: t = |n̂·(v0 − eye)| / (σ n̂·d), in front where the denominator is positive.
  const double sigma = w.eyeDistance >= 0 ? 1 : -1;
  const auto nc = constants(w.normal * sigma);
  const Fixed ncc[3] = {nc[0], nc[1], nc[2]};
  const Multi den = Dot3(d, ncc, unit);
  const Multi num = Broadcast(m, Tight(std::abs(w.eyeDistance), F));
  Candidate out;
  const Multi front = zero < den;
  const Multi cand = front && (inside || edgeUncertain);
  Where(cand, [&] { out.t = Div(num, den, pf.t, kSaturate); });
  const Multi hither = Broadcast(m, Tight(pf.hither, F));
  out.hit = cand && inside && (hither < out.t);
  const Multi nearHither = b.alwaysUncertain ? Broadcast(m, Fixed{Format::Unsigned(1, 0), 1})
                                             : Near(m, out.t - hither, b.tError + pf.Ulp(), F);
  out.uncertain = cand && (edgeUncertain || nearHither);
  out.tLow = SubBound(m, out.t, b.slack, pf.t);
  return out;
}

Multi Linear(const Multi (&d)[3], const LinearForm& l, int frac) {
  const Fixed c[3] = {Tight(l.c.x, frac), Tight(l.c.y, frac), Tight(l.c.z, frac)};
  return Dot3(d, c, l.format);
}

Multi SumOfSquares(const Multi (&x)[3], Format f) {
  return Add(Add(Square(x[0], f), Square(x[1], f), f), Square(x[2], f), f);
}

// One root of the cone: t = ±N/D where |D| >= D* (`sure`), or certainly outside the cone's
// range [tNear, tFar] of t (`beyond`: no hit), or neither (uncertain). See ConeDivision.
struct ConeRoot {
  Multi t, sure, beyond;
};

// Certainly |N/D| outside [tNear, tFar] (no point of the cone there), for |N| and |D| with
// errors eN and eD: |N| − eN >= tFar·(|D| + eD), or |N| + eN <= tNear·(|D| − eD). Products
// round down and constants to nearest, which the margins absorb.
Multi Outside(Machine& m, const Multi& absN, const Multi& absD, double eN, double eD, double tNear,
              double tFar, int frac) {
  const double u = std::ldexp(1.0, -frac);
  const Format bf = Format::Unsigned(absD.Format().intBits + IntBitsFor(tFar + u) + 1, frac);
  const Multi far = Add(Mul(absD, Uni{Tight(tFar + u, frac)}, bf), Broadcast(m, Tight(tFar * eD + eN + 3 * u, frac)), bf);
  Multi out = far <= absN;
  if (tNear > 0) {
    const Multi near = Mul(absD, Uni{Tight(std::max(tNear - u, 0.0), frac)}, bf);
    const Format nf = Format::Unsigned(absN.Format().intBits + 1, frac);
    out = out || (Add(absN, Broadcast(m, Tight(tNear * eD + eN + 2 * u, frac)), nf) <= near);
  }
  return out;
}

Multi AbsOf(const Multi& x) { return Abs(x, Format::Unsigned(x.Format().intBits + 1, x.Format().fracBits)); }

ConeRoot ConeDivide(Machine& m, const Multi& n, const Multi& den, const Multi& negate, const Multi& active,
                    const ConeDivision& v, double tNear, double tFar, int frac) {
  ConeRoot r;
  const Multi absD = AbsOf(den);
  r.sure = Broadcast(m, Tight(v.dStar, frac)) <= absD;
  r.beyond = Outside(m, AbsOf(n), absD, v.eN, v.eD, tNear, tFar, frac);
  WithExpectedSaturation(m, [&] {  // a saturated quotient is >= tCut: beyond the cone
    Where(active && r.sure, [&] { r.t = Div(n, den, v.out, kSaturate); });
    Where(negate, [&] { r.t = Neg(r.t, v.out, kSaturate); });
  });
  return r;
}

Candidate TestCone(Machine& m, const Primitive& p, const Vec3& eye, const Multi (&d)[3],
                   const PassFormats& pf, const ObjectBounds& b) {
  const int F = pf.fracBits;
  const double u = pf.Ulp();
  const ConeSetup cs = MakeConeSetup(p, eye, pf);
  auto uni = [&](double x) { return Broadcast(m, Tight(x, F)); };
  Candidate out;
  const Multi zero = Zero(m);
  if (cs.empty) {  // no height has a non-negative radius
    out.t = Broadcast(m, Fixed{pf.t, pf.t.MaxRaw()});
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
  const Multi aq = Length(cs.g.c) > 0 ? Sub(sumU, Square(Linear(d, cs.g, F), cs.aFormat), cs.aFormat)
                                      : Convert(sumU, cs.aFormat);
  const Multi disc = Sub(SumOfSquares(ev, cs.sum3Disc), Square(Linear(d, cs.q, F), cs.discFormat), cs.discFormat);
  const Multi roots = uni(cs.grazeBand) <= disc;  // certainly two roots (of the infinite cone)
  Multi grazing = Near(m, disc, cs.grazeBand, F);
  const Multi root = Sqrt(disc, cs.rootFormat);
  // Q = |β| + √disc; t = −sgn(β)·Q/A and −sgn(β)·C/Q (the stable pair).
  const Multi q = Add(AbsOf(beta), root, cs.qFormat);
  const Multi negate = zero <= beta;
  const ConeRoot rs[2] = {ConeDivide(m, q, aq, negate, roots, cs.divA, cs.tNear, cs.tFar, F),
                          ConeDivide(m, uni(cs.C), q, negate, roots, cs.divC, cs.tNear, cs.tFar, F)};
  // A grazing ray matters only if the double root could lie in [tNear, tFar]: there Q is
  // within eβ + √(G + e_disc) of its true value (both roots of the true disc >= 0 are).
  {
    const double eQg = cs.beta.err + std::sqrt(cs.grazeBand + cs.eDisc) + u;
    const Multi absQ = AbsOf(q), absC = AbsOf(uni(cs.C));
    grazing = grazing && !(Outside(m, absQ, AbsOf(aq), eQg, cs.eA, cs.tNear, cs.tFar, F) &&
                           Outside(m, absC, absQ, u / 2, eQg, cs.tNear, cs.tFar, F));
  }
  const ConeDivision* divs[2] = {&cs.divA, &cs.divC};
  const Multi hither = uni(pf.hither), sLo = uni(cs.sLo), sHi = uni(cs.sHi);
  const Fixed tMax{pf.t, pf.t.MaxRaw()};
  Multi valid[2], unsure[2], low[2];
  for (int i = 0; i < 2; ++i) {
    const ConeDivision& v = *divs[i];
    const ConeRoot& r = rs[i];
    // The height of the hit: s = w·a + t·(d'·a).
    Multi s;
    WithExpectedSaturation(m, [&] { s = Add(Mul(r.t, da, cs.sFormat[i], kSaturate), uni(cs.wa), cs.sFormat[i], kSaturate); });
    const Multi inRange = roots && r.sure && (r.t < uni(v.tCut));
    valid[i] = inRange && (hither < r.t) && (sLo < s) && (s < sHi);
    const Multi notBehind = uni(pf.hither - v.tError - u) < r.t;
    const Multi rim = Near(m, r.t - hither, v.tError + u, F) || Near(m, s - sLo, cs.eS[i] + u, F) ||
                      Near(m, s - sHi, cs.eS[i] + u, F);
    unsure[i] = (roots && !r.sure && !r.beyond) || (inRange && notBehind && rim);
    // Where uncertain, the true root (if a hit) is >= low.
    WithExpectedSaturation(m, [&] {
      const Multi lowSure = Sub(r.t, uni(v.tError + u), pf.t, kSaturate);
      low[i] = Select(r.sure, lowSure, Select(r.beyond, Broadcast(m, tMax), uni(cs.tNear), pf.t), pf.t, kSaturate);
    });
  }
  out.hit = valid[0] || valid[1];
  WithExpectedSaturation(m, [&] {
    out.t = Select(valid[0] && (!valid[1] || rs[0].t < rs[1].t), rs[0].t, rs[1].t, pf.t, kSaturate);
  });
  out.uncertain = grazing || unsure[0] || unsure[1];
  out.tLow = Select(grazing, uni(cs.tNear), Min(low[0], low[1], pf.t), pf.t);
  if (b.alwaysUncertain) {  // the bounds do not close: every PE that may hit is flagged
    out.uncertain = uni(-cs.grazeBand) < disc;
    out.tLow = Convert(uni(cs.tNear), pf.t);
  }
  return out;
}

}  // namespace

Candidate TestObject(Machine& m, const Scene& scene, int index, const Multi (&d)[3],
                     const PassFormats& pf, const ObjectBounds& b) {
  const Primitive& p = scene.objects[index];
  switch (p.Kind()) {
    case ShapeKind::kSphere:
      return p.transform ? TestEllipsoid(m, p, scene.camera.from, d, pf, b)
                         : TestSphere(m, std::get<Sphere>(p.shape), scene.camera.from, d, pf, b);
    case ShapeKind::kPolygon:
      return TestPolygon(m, p, scene.camera.from, d, pf, b);
    case ShapeKind::kCone:
      return TestCone(m, p, scene.camera.from, d, pf, b);
  }
  ZEPHYR_CHECK(false);
  return {};
}

}  // namespace zephyr::simd
