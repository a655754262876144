// hosts/simd_shapes.cpp — the per-primitive array programs of the SIMD primary pass and the
// host-side error analysis that makes their uncertain-pixel flags sound (docs/simd.md).
#include "hosts/simd_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "fixed/check.h"
#include "hosts/simd_ops.h"

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
  b.onArray = false;  // cones: on the host in double
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

}  // namespace

Candidate TestObject(Machine& m, const Scene& scene, int index, const Multi (&d)[3],
                     const PassFormats& pf, const ObjectBounds& b) {
  const Primitive& p = scene.objects[index];
  ZEPHYR_CHECK(b.onArray);
  switch (p.Kind()) {
    case ShapeKind::kSphere:
      return p.transform ? TestEllipsoid(m, p, scene.camera.from, d, pf, b)
                         : TestSphere(m, std::get<Sphere>(p.shape), scene.camera.from, d, pf, b);
    case ShapeKind::kPolygon:
      return TestPolygon(m, p, scene.camera.from, d, pf, b);
    case ShapeKind::kCone:
      break;
  }
  ZEPHYR_CHECK(false);
  return {};
}

}  // namespace zephyr::simd
