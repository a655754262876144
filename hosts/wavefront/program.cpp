// hosts/wavefront/program.cpp — one wavefront bounce on the array (hosts/wavefront/program.h,
// docs/wavefront.md "The bounce program" and "Error bounds").
#include "hosts/wavefront/program.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fixed/check.h"
#include "hosts/simd/bounds.h"
#include "hosts/simd/ops.h"

namespace zephyr::wavefront {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;
using simd::IntBitsFor;
using simd::Tight;

namespace {

// 1/|m| of a patch's interpolated normal below 2^8 (its vertex normals scaled to length <= 1;
// a shorter m, normals nearly opposite, overflows the division: the ray is flagged).
constexpr int kPatchNormalBits = 8;

// The extra fraction bits of an ellipsoid's object space (PlanEllipsoid) and of a cone's local
// frame (PlanCone: its discriminant has no Hearn–Baker form, its terms are as large as the
// scene's squares, and its error must stay far below its grazing band).
constexpr int kEllipsoidExtraBits = 10, kConeExtraBits = 20;

// An ellipsoid's object space and bounds (docs/wavefront.md, "Ellipsoids"): the primary
// pass's ellipsoid analysis (hosts/simd/ellipsoid.cpp) with the origin a multi too. Along the
// array's own ray (o, d exact; |o_j| <= extent, |d|² within δ of 1): o − anchor carries the
// anchor's rounding (u/2), each of M's entries is rounded to nearest (u/2) and each product
// floor-rounded (u); the reference maps the ray through the scene's double T⁻¹, covered by a
// relative 1e-12. Then f·d', f×d', |d'|² and r²|d'|² by MulErr / SquareErr, the band from
// GrazingBand with the primary pass's radius/8 floor, and t = num/|d'|² with |d'|² >= ddMin
// (σ_min(M) >= 1/‖T‖_F).
SphereTerms PlanEllipsoid(const Primitive& o, const Sphere& s, const std::vector<Light>& lights,
                          double extent, double diameter, const SecondaryPlan& p, int F) {
  // The object space at Fl = F + kEllipsoidExtraBits fraction bits, M's entries at Fl + 4:
  // o' is as large as the scene (|o − anchor| up to its diameter) and enters the cross
  // product, whose error sets the grazing band and the root's error; at F they would give
  // t errors of 0.1 at 64×64 with the eye 8 away (F = 18).
  const int Fl = F + kEllipsoidExtraBits, Fm = Fl + 4;
  const double u = std::ldexp(1.0, -F), ul = std::ldexp(1.0, -Fl), um = std::ldexp(1.0, -Fm);
  const double delta = p.directionError;
  const Affine inv = o.transform->Inverse();
  const Vec3 anchor = o.transform->ApplyPoint(s.centre);
  SphereTerms t;
  EllipsoidTerms e;
  double fn = 0;  // ‖T‖_F²
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) fn += o.transform->m[i][j] * o.transform->m[i][j];
  const double dl = 1 + delta;  // |d_j| <= |d| <= √(1 + δ)
  double eO[3], mO[3], eD[3], mD[3];
  for (int k = 0; k < 3; ++k) {
    e.anchor[k] = Tight(anchor[k], Fl);
    eO[k] = mO[k] = eD[k] = mD[k] = 0;
    for (int j = 0; j < 3; ++j) {
      e.inverse[k][j] = Tight(inv.m[k][j], Fm);
      const double a = std::abs(inv.m[k][j]), x = extent + std::abs(anchor[j]) + ul / 2;
      eO[k] += simd::MulErr(x, ul / 2, a, um / 2, ul);
      eD[k] += simd::MulErr(dl, 0, a, um / 2, ul);
      mO[k] += a * x, mD[k] += a * dl;
    }
    eO[k] += 1e-12 * (mO[k] + 1), eD[k] += 1e-12 * (mD[k] + 1);
    mO[k] += eO[k], mD[k] += eD[k];
  }
  e.offset = Format::Signed(p.intBits + 1, Fl);
  double eTcaN = 0, eCross = 0, eDd = 0, oo = 0, ddMax = 0;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    eTcaN += simd::MulErr(mO[k], eO[k], mD[k], eD[k], ul);
    eCross = std::max(eCross, simd::MulErr(mO[i], eO[i], mD[j], eD[j], ul) +
                                  simd::MulErr(mO[j], eO[j], mD[i], eD[i], ul));
    eDd += simd::SquareErr(mD[k], eD[k], ul);
    oo += mO[k] * mO[k], ddMax += mD[k] * mD[k];
  }
  ddMax += eDd;
  const double ddMin = (1 - delta) / fn - eDd;
  if (!(ddMin > 0))
    throw UserError(
        o.where.ToString() + ": this ellipsoid is too thin for the array's rays at " +
        std::to_string(F) +
        " fraction bits (|T⁻¹d|² may round to 0): give the secondary rays more fraction "
        "bits (docs/wavefront.md, \"Ellipsoids\")");
  const double r = s.radius, r2 = r * r;
  const int R = IntBitsFor(r * std::sqrt(ddMax));
  for (int k = 0; k < 3; ++k) {
    e.local[k] = Format::Signed(IntBitsFor(mO[k]) + 1, Fl);
    e.dLocal[k] = Format::Signed(IntBitsFor(mD[k]) + 1, Fl);
  }
  e.products = Format::Signed(IntBitsFor(std::sqrt(oo * ddMax)) + 1, Fl);
  e.dd = Format::Unsigned(IntBitsFor(ddMax + 1), Fl);
  e.numerator = Format::Signed(e.products.intBits + 1, Fl);
  e.fracBits = Fl;
  t.clamped = Format::Signed(R, Fl), t.square = Format::Unsigned(2 * R + 2, Fl);
  t.disc = Format::Signed(2 * R + 2, Fl), t.root = Format::Unsigned(R + 1, Fl);
  t.r2 = Tight(r2, Fl);
  const double eR2dd = r2 * eDd + ddMax * ul / 2 + ul;
  const auto [band, eDisc] =
      simd::GrazingBand(r2 * ddMax, r2 * ddMin / 64, eCross, eR2dd, std::ldexp(1.0, R), ul);
  t.grazeBand = band;
  const double eNum = eTcaN + eDisc / std::sqrt(band) + ul;
  const double tFar = diameter / (1 - delta);
  t.tError = eNum / ddMin + tFar * eDd / ddMin + u;
  t.slack = t.tError + 2 * std::sqrt(band + eDisc) / ddMin + u;
  for (const Light& l : lights)
    t.lightOutside.push_back(Length(inv.ApplyVector(l.position - anchor)) > r);
  // The normal Mᵀ·o' scaled by 1/(r·‖M‖_F): |·| <= 1 (|o'| = r on the surface) and
  // >= 1/(‖M‖_F·‖T‖_F), the reach of Normalise's inverse (SecondaryPlan::normalInverseBits).
  double mf = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) mf += inv.m[i][j] * inv.m[i][j];
  mf = std::sqrt(mf);
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) t.normalScale[j][k] = Tight(inv.m[j][k] / (r * mf), F);
  t.normalInverseBits = IntBitsFor(1.01 * mf * std::sqrt(fn)) + 1;
  t.ellipsoid = e;
  return t;
}

// A cone's local frame, formats and bounds (ConeTerms; docs/wavefront.md "Cones"), along the
// array's own ray as PlanEllipsoid: the frame's entries rounded to nearest at Fl + 4, the
// anchor at Fl, each product floor-rounded at Fl; every quantity's error from MulErr /
// SquareErr over its operands' bounds; the discriminant's grazing band at least twice its
// error and (r_max/64)²/64; the two divisions by PlanDivision with the parallel threshold
// |A| >= 1/64 and |Q| >= √G − ulp (where disc >= G).
ConeTerms PlanCone(const Primitive& o, const Cone& cone, double extent, double diameter,
                   const SecondaryPlan& p, int F) {
  const int Fl = F + kConeExtraBits, Fm = Fl + 4;
  const double ul = std::ldexp(1.0, -Fl), um = std::ldexp(1.0, -Fm);
  const double delta = p.directionError;
  ZEPHYR_CHECK(cone.baseRadius >= 0 && cone.apexRadius >= 0);  // the NFF reader's rule
  double inv[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 anchor = cone.base;
  double forward = std::sqrt(3.0);  // ‖T‖_F
  if (o.transform) {
    const Affine a = o.transform->Inverse();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) inv[i][j] = a.m[i][j];
    anchor = o.transform->ApplyPoint(cone.base);
    double fn = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) fn += o.transform->m[i][j] * o.transform->m[i][j];
    forward = std::sqrt(fn);
  }
  const Vec3 axisVector = cone.apex - cone.base;  // object space
  const double h = Length(axisVector);
  const Vec3 axis = axisVector / h;
  const Vec3 e1 = Normalize(Cross(axis, std::abs(axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
  const Vec3 e2 = Cross(axis, e1);
  const Vec3 rows[3] = {e1, e2, axis};
  double frame[3][3], frob = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      frame[i][j] = rows[i].x * inv[0][j] + rows[i].y * inv[1][j] + rows[i].z * inv[2][j];
      frob += frame[i][j] * frame[i][j];
    }
  frob = std::sqrt(frob);
  ConeTerms t;
  t.fracBits = Fl;
  const double dl = 1 + delta;
  double eO[3], mO[3], eD[3], mD[3];
  for (int k = 0; k < 3; ++k) {
    t.anchor[k] = Tight(anchor[k], Fl);
    eO[k] = mO[k] = eD[k] = mD[k] = 0;
    for (int j = 0; j < 3; ++j) {
      t.frame[k][j] = Tight(frame[k][j], Fm);
      const double a = std::abs(frame[k][j]), x = extent + std::abs(anchor[j]) + ul / 2;
      eO[k] += simd::MulErr(x, ul / 2, a, um / 2, ul);
      eD[k] += simd::MulErr(dl, 0, a, um / 2, ul);
      mO[k] += a * x, mD[k] += a * dl;
    }
    eO[k] += 1e-12 * (mO[k] + 1), eD[k] += 1e-12 * (mD[k] + 1);
    mO[k] += eO[k], mD[k] += eD[k];
  }
  const double r0 = cone.baseRadius, r1 = cone.apexRadius, sigma = (r1 - r0) / h;
  const double as = std::abs(sigma), rMax = std::max(r0, r1);
  t.r0 = Tight(r0, Fl), t.sigma = Tight(sigma, Fm), t.height = Tight(h, Fl);
  auto fmt = [&](double bound) { return Format::Signed(IntBitsFor(bound) + 1, Fl); };
  for (int k = 0; k < 3; ++k) t.local[k] = fmt(mO[k]), t.dLocal[k] = fmt(mD[k]);
  t.offset = Format::Signed(p.intBits + 1, Fl);
  // ρ = r0 + σ·o_z; σd_z.
  const double eRho = simd::MulErr(mO[2], eO[2], as, um / 2, ul) + ul / 2;
  const double mRho = r0 + as * mO[2] + eRho;
  const double eSdz = simd::MulErr(mD[2], eD[2], as, um / 2, ul), mSdz = as * mD[2] + eSdz;
  const double eA = simd::SquareErr(mD[0], eD[0], ul) + simd::SquareErr(mD[1], eD[1], ul) +
                    simd::SquareErr(mSdz, eSdz, ul);
  const double mA = mD[0] * mD[0] + mD[1] * mD[1] + mSdz * mSdz + eA;
  const double eBeta = simd::MulErr(mO[0], eO[0], mD[0], eD[0], ul) +
                       simd::MulErr(mO[1], eO[1], mD[1], eD[1], ul) +
                       simd::MulErr(mRho, eRho, mSdz, eSdz, ul);
  const double mBeta = mO[0] * mD[0] + mO[1] * mD[1] + mRho * mSdz + eBeta;
  const double eC = simd::SquareErr(mO[0], eO[0], ul) + simd::SquareErr(mO[1], eO[1], ul) +
                    simd::SquareErr(mRho, eRho, ul);
  const double mC = mO[0] * mO[0] + mO[1] * mO[1] + mRho * mRho + eC;
  double eG = 0, mG = 0;
  for (int k = 0; k < 2; ++k) {
    eG = std::max(eG, simd::MulErr(mRho, eRho, mD[k], eD[k], ul) +
                          simd::MulErr(mSdz, eSdz, mO[k], eO[k], ul));
    mG = std::max(mG, mRho * mD[k] + mSdz * mO[k]);
  }
  mG += eG;
  const double eCross =
      simd::MulErr(mD[0], eD[0], mO[1], eO[1], ul) + simd::MulErr(mD[1], eD[1], mO[0], eO[0], ul);
  const double mCross = mD[0] * mO[1] + mD[1] * mO[0] + eCross;
  const double eDisc = 2 * simd::SquareErr(mG, eG, ul) + simd::SquareErr(mCross, eCross, ul);
  const double mDisc = 2 * mG * mG + mCross * mCross + eDisc;
  const double parallel = 1.0 / 64;
  t.grazeBand = std::max(2 * eDisc, std::pow(rMax / 8, 2) * parallel);
  const double eRoot = eDisc / std::sqrt(t.grazeBand) + ul, eQ = eBeta + eRoot;
  const double mQ = mBeta + std::sqrt(mDisc) + eQ;
  const double tFar = diameter / (1 - delta), target = 1e-2;
  t.tFar = tFar;
  t.divA = simd::PlanDivision(eQ, eA, tFar, target, parallel, F);
  t.divC = simd::PlanDivision(eC, eQ, tFar, target, std::sqrt(t.grazeBand) - ul, F);
  // Grazing (|disc| < G): the true √disc is in [0, √(G + e_disc)], so Q is within
  // e_β + √(G + e_disc); bounds loose enough for the rare grazing ray only to say whether a root
  // is certainly behind, beyond or out of height.
  const double eQGrazing = eBeta + std::sqrt(t.grazeBand + eDisc) + ul;
  t.divAGrazing = simd::PlanDivision(eQGrazing, eA, tFar, 0.1, parallel, F);
  t.divCGrazing = simd::PlanDivision(eC, eQGrazing, tFar, 0.1, 0, F);
  t.tError = std::max(t.divA.tError, t.divC.tError);
  double tRange = 0;
  const simd::ConeDivision* divs[2][2] = {{&t.divA, &t.divC}, {&t.divAGrazing, &t.divCGrazing}};
  for (int g = 0; g < 2; ++g)
    for (int r = 0; r < 2; ++r) {
      const simd::ConeDivision& v = *divs[g][r];
      t.heightError[g][r] = eO[2] + simd::MulErr(v.tRange, v.tError, mD[2], eD[2], ul) + ul;
      tRange = std::max(tRange, v.tRange);
    }
  t.rho = fmt(mRho), t.sigmaDz = fmt(mSdz), t.a = fmt(mA), t.beta = fmt(mBeta), t.c = fmt(mC);
  t.g = fmt(mG), t.cross = fmt(mCross);
  t.square = Format::Unsigned(IntBitsFor(mDisc) + 1, Fl), t.disc = fmt(mDisc);
  t.root = Format::Unsigned(IntBitsFor(std::sqrt(mDisc)) + 1, Fl);
  t.q = Format::Unsigned(IntBitsFor(mQ) + 1, Fl);
  t.s = fmt(mO[2] + tRange * mD[2]);
  if (t.disc.Width() > 120)
    throw UserError(
        o.where.ToString() + ": this cone's discriminant would take " +
        std::to_string(t.disc.Width()) +
        " bits on the array (at most 120): give the secondary rays fewer fraction bits");
  // The normal frameᵀ·(x_L, y_L, −σρ) at the hit, scaled to length <= 1; its reciprocal up to
  // ‖frame‖_F·‖frame⁻¹‖_F·r_max/max(r_min, r_max/256) (a normal near an apex is shorter).
  const double scale = 1 / (rMax * std::sqrt(1 + sigma * sigma) * frob);
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) t.normalScale[j][k] = Tight(frame[j][k] * scale, F);
  const double rMin = std::max(std::min(r0, r1), rMax / 256);
  t.normalInverseBits = IntBitsFor(1.01 * frob * forward * rMax / rMin) + 1;
  return t;
}

// A polygon patch's fan triangles and vertex normals (PolygonTerms::fan): the tracer's
// Barycentric weights of P in (a, b, c), v = ((d11·v0 − d01·v1)/den)·(P − a) and
// w = ((d00·v1 − d01·v0)/den)·(P − a) with v0 = b − a, v1 = c − a, d_ij their dot products and
// den = d00·d11 − d01²; a triangle whose den is 0 (its weights not finite in the tracer) never
// holds P. The normals are scaled by one factor so the largest has length 1: the interpolated
// normal is normalised after, so the factor does not change it.
void PlanPatch(const std::vector<Vec3>& v, const std::vector<Vec3>& normals, double diameter, int F,
               PolygonTerms& t) {
  if (normals.empty()) return;
  double most = 0, reach = 1;
  for (const Vec3& n : normals) most = std::max(most, Length(n));
  for (const Vec3& n : normals) {
    const Vec3 x = most > 0 ? n / most : n;
    t.vertexNormals.push_back({Tight(x.x, F), Tight(x.y, F), Tight(x.z, F)});
  }
  for (size_t i = 1; i + 1 < v.size(); ++i) {
    const Vec3 v0 = v[i] - v[0], v1 = v[i + 1] - v[0];
    const double d00 = Dot(v0, v0), d01 = Dot(v0, v1), d11 = Dot(v1, v1);
    const double den = d00 * d11 - d01 * d01;
    const Vec3 alpha = (v0 * d11 - v1 * d01) / den, beta = (v1 * d00 - v0 * d01) / den;
    if (!(std::isfinite(MaxAbs(alpha)) && std::isfinite(MaxAbs(beta))) || den == 0) continue;
    PolygonTerms::FanTriangle f;
    for (int k = 0; k < 3; ++k) f.alpha[k] = Tight(alpha[k], F), f.beta[k] = Tight(beta[k], F);
    f.i = int(i);
    t.fan.push_back(f);
    const double a1 = std::abs(alpha.x) + std::abs(alpha.y) + std::abs(alpha.z);
    const double b1 = std::abs(beta.x) + std::abs(beta.y) + std::abs(beta.z);
    reach = std::max(reach, 1 + (a1 + b1) * diameter);
  }
  t.weight = Format::Signed(IntBitsFor(reach) + 1, F);
}

// What the plan needs of the scene before any format is chosen: the largest coordinate any
// ray or object reaches, the farthest light, the largest index of refraction either way, and
// each polygon's world form (ToWorldSpace, as the tracer and the primary pass take it). Also
// fills p.objects (each object's kind and its index among its kind's terms, whose entries
// PlanObjects fills) and p.anyMirror, p.anyTransparent.
struct SceneSurvey {
  double extent = 0, light = 0, maxIor = 1;
  std::vector<std::vector<Vec3>> worldVertices, worldVertexNormals;
  std::vector<Vec3> worldNormals;  // unit, turned by a mirroring transform (front·normal)
};

SceneSurvey Survey(const Scene& scene, SecondaryPlan& p) {
  SceneSurvey v;
  v.extent = MaxAbs(scene.camera.from);
  for (const Primitive& o : scene.objects) {
    const auto* s = std::get_if<Sphere>(&o.shape);
    if (const auto* c = std::get_if<Cone>(&o.shape)) {
      const double r = std::max(std::abs(c->baseRadius), std::abs(c->apexRadius));
      v.extent = std::max(
          v.extent, o.transform ? MaxAbs(o.transform->ApplyPoint(c->base)) +
                                      o.transform->LinearNormInf() * (MaxAbs(c->apex - c->base) + r)
                                : std::max(MaxAbs(c->base), MaxAbs(c->apex)) + r);
      p.objects.push_back({false, int(p.cones.size()), true});
      p.cones.emplace_back();
    } else if (s) {
      v.extent = std::max(v.extent, o.transform ? MaxAbs(o.transform->ApplyPoint(s->centre)) +
                                                      s->radius * o.transform->LinearNormInf()
                                                : MaxAbs(s->centre) + s->radius);
      p.objects.push_back({true, int(p.spheres.size())});
      p.spheres.emplace_back();
    } else {
      p.objects.push_back({false, int(v.worldVertices.size())});
      WorldSpacePolygon world = ToWorldSpace(o);  // as the tracer and the primary pass take it
      for (const Vec3& x : world.vertices) v.extent = std::max(v.extent, MaxAbs(x));
      v.worldNormals.push_back(world.normal * double(world.front));
      v.worldVertices.push_back(std::move(world.vertices));
      v.worldVertexNormals.push_back(std::move(world.normals));
    }
    const Material& m = scene.materials[o.material];
    v.maxIor = std::max({v.maxIor, m.ior, 1 / m.ior});
    p.anyMirror |= m.ks > 0;
    p.anyTransparent |= m.t > 0;
  }
  for (const Light& l : scene.lights) v.light = std::max(v.light, MaxAbs(l.position));
  return v;
}

// The formats at F fraction bits for the survey's extent, lights and indices; refused when a
// coordinate or the widest value would not fit what the host and the engine read.
void ChooseFormats(SecondaryPlan& p, const SceneSurvey& v, int F, size_t objects) {
  const double u = std::ldexp(1.0, -F);
  p.fracBits = F, p.ulp = u;
  p.intBits = IntBitsFor(v.extent) + 1;
  const int I = p.intBits;
  p.coord = Format::Signed(I, F);
  p.offset = Format::Signed(I + 1, F);
  p.t = Format::Signed(I + 2, F);
  p.direction = Format::Signed(1, F);
  const int il = IntBitsFor(v.light + v.extent) + 1;
  p.toLight = Format::Signed(il, F);
  p.distance = Format::Unsigned(il, F);
  p.eta = Format::Unsigned(IntBitsFor(v.maxIor) + 1, F);
  p.unit = Format::Unsigned(1, F);
  p.index = Format::Unsigned(IntBitsFor(double(objects) + 1) + 1, 0);
  // The host reads coordinates as 64-bit integers and the engine's widest value has 128 bits
  // (the polygon edge functions' are the widest here).
  const bool polygons = !v.worldVertices.empty();
  const int widest = !polygons ? p.t.Width() : 2 * I + 8 + F;
  if (p.coord.Width() > 62 || widest > 120)
    throw UserError("the scene's extent (" + fmt::format("{:.6g}", v.extent) + ") needs " +
                    std::to_string(I) + " integer bits: with " + std::to_string(F) +
                    " fraction bits a coordinate would take " + std::to_string(p.coord.Width()) +
                    " bits (at most 62: the host reads it as a 64-bit integer) and the widest "
                    "value " +
                    std::to_string(widest) +
                    " (at most 120): use fewer fraction "
                    "bits, at most " +
                    std::to_string(std::min(61 - I, !polygons ? 61 - I : 112 - 2 * I)));
  p.edgeVector = Format::Signed(I + 2, F);
  p.edgeCross = Format::Signed(2 * I + 5, F);
  p.edgeValue = Format::Signed(2 * I + 7, F);
  // A direction normalised on the array (d·(1/|d|), each step floor-rounded): | |d|² − 1 |
  // below 12u (docs/wavefront.md, "Error bounds"); 16u taken.
  p.directionError = 16 * u;
}

// Polygons (docs/wavefront.md, "Error bounds"): each edge function's error from the vertices
// rounded to nearest (|p − o|, |q − o| <= the diameter D) and five floor products; t =
// (n·v0 − n·o)/(n·d) with n and n·v0 rounded to nearest, where |n·d| >= the parallel band.
void PlanPolygons(SecondaryPlan& p, const SceneSurvey& v, double D, int F) {
  const double u = p.ulp;
  const double eNum = 3 * std::ldexp(1.0, p.intBits) * u / 2 + 3 * u + u / 2,
               eNd = 1.75 * u / 2 + 3 * u;
  const double edgeBand = 1.25 * (1.75 * (2 * D * u + 2 * u + u * u) + 3 * u);
  double rungs[3];
  for (int k = 0; k < 3; ++k)
    rungs[k] = (eNum + D * eNd) / (kPolygonRungs[k] - eNd) + D * p.directionError + 2 * u;
  const double tError = rungs[0];
  for (size_t j = 0; j < v.worldVertices.size(); ++j) {
    PolygonTerms t;
    const Vec3& n = v.worldNormals[j];
    for (int k = 0; k < 3; ++k) t.normal[k] = Tight(n[k], F);
    t.offset = Tight(Dot(n, v.worldVertices[j][0]), F);
    for (const Vec3& x : v.worldVertices[j])
      t.vertices.push_back({Tight(x.x, F), Tight(x.y, F), Tight(x.z, F)});
    t.groups = PolygonEdgeGroups(v.worldVertices[j], n);
    t.edgeBand = edgeBand, t.tError = tError;
    for (int k = 0; k < 3; ++k) t.tErrorRung[k] = rungs[k];
    PlanPatch(v.worldVertices[j], v.worldVertexNormals[j], D, F, t);
    p.polygons.push_back(t);
  }
}

// An untransformed sphere's terms: its centre, r² and 1/r at F, its formats, its grazing band
// and t error.
SphereTerms PlanSphere(const Primitive& o, const Sphere& s, const std::vector<Light>& lights,
                       double diameter, const SecondaryPlan& p, int F) {
  const double u = p.ulp;
  const double eTca = 4 * u;    // Σ d_k (c_k − o_k): c rounded to nearest, 3 floor products
  const double eCross = 3 * u;  // f_j d_l − f_l d_j
  SphereTerms t;
  // 1/r (the normal's scale) must fit the engine's widest number beside F fraction bits.
  if (IntBitsFor(1 / s.radius) + 1 + F > fixed::kMaxWidth)
    throw UserError(fmt::format(
        "{}: a sphere of radius {:.3g} is too small for the array's secondary rays at {} "
        "fraction bits (1/r needs {} integer bits; docs/wavefront.md, \"Formats\"): render it "
        "with the seq, simd or hetero method (--method)",
        o.where.ToString(), s.radius, F, IntBitsFor(1 / s.radius)));
  for (int k = 0; k < 3; ++k) t.centre[k] = Tight(s.centre[k], F);
  t.r2 = Tight(s.radius * s.radius, F);
  t.inverseRadius = Tight(1 / s.radius, F);
  const int R = IntBitsFor(s.radius);
  t.clamped = Format::Signed(R, F), t.square = Format::Unsigned(2 * R + 2, F);
  t.disc = Format::Signed(2 * R + 2, F), t.root = Format::Unsigned(R + 1, F);
  const double r2 = s.radius * s.radius;
  // The band as the primary pass's (the radius/8 floor), grown by the direction's
  // non-unit length: r² − |f×d|² against r² − |f×d̂|² differs by <= (r² + G)·δ.
  double g = r2 / 64, eDisc = 0;
  for (int it = 0; it < 8; ++it) {
    const auto [band, e] = simd::GrazingBand(r2, g, eCross, u / 2, std::ldexp(1.0, R), u);
    eDisc = e + 1.01 * p.directionError * (r2 + band);
    g = std::max(band, 2 * eDisc);
    if (2 * eDisc <= g && band <= g) break;
  }
  t.grazeBand = g;
  // f·d along the array's d against f·d̂: |f|·| |d| − 1 |.
  const double eDir = diameter * p.directionError;
  t.tError = eTca + eDir + eDisc / std::sqrt(g) + 2 * u;
  t.slack = std::max(t.tError, eTca + eDir + std::sqrt(g + eDisc)) + u;
  for (const Light& l : lights) t.lightOutside.push_back(Length(l.position - s.centre) > s.radius);
  return t;
}

// Every object's terms, each with its material's transparency and index, and the plan's
// largest t error and normal inverse bits over them.
void PlanObjects(const Scene& scene, SecondaryPlan& p, double extent, double diameter, int F) {
  for (size_t j = 0; j < scene.objects.size(); ++j) {
    const Primitive& o = scene.objects[j];
    const Material& m = scene.materials[o.material];
    if (p.objects[j].cone) {
      ConeTerms t = PlanCone(o, std::get<Cone>(o.shape), extent, diameter, p, F);
      t.transparency = m.t, t.ior = m.ior;
      p.tError = std::max(p.tError, t.tError);
      p.normalInverseBits = std::max(p.normalInverseBits, t.normalInverseBits);
      p.cones[p.objects[j].index] = t;
      continue;
    }
    if (!p.objects[j].sphere) {
      PolygonTerms& t = p.polygons[p.objects[j].index];
      t.transparency = m.t, t.ior = m.ior;
      p.tError = std::max(p.tError, t.tError);
      continue;
    }
    const Sphere& s = std::get<Sphere>(o.shape);
    SphereTerms t = o.transform ? PlanEllipsoid(o, s, scene.lights, extent, diameter, p, F)
                                : PlanSphere(o, s, scene.lights, diameter, p, F);
    t.transparency = m.t, t.ior = m.ior;
    p.tError = std::max(p.tError, t.tError);
    p.spheres[p.objects[j].index] = t;
  }
  for (const SphereTerms& t : p.spheres)
    p.normalInverseBits = std::max(p.normalInverseBits, t.normalInverseBits);
  for (const PolygonTerms& t : p.polygons)
    if (!t.fan.empty()) p.normalInverseBits = std::max(p.normalInverseBits, kPatchNormalBits);
}

// The hit point's slack, the array's cut-off ε and the error format, from the object terms.
void PlanSlacks(SecondaryPlan& p, double diameter) {
  const double u = p.ulp;
  // A hit point's distance from its surface: t's error along |d| <= 1 + δ, t·| |d| − 1 |, and
  // the point's own rounding; a ray leaving it ignores roots up to four times that.
  p.pointSlack = diameter * p.directionError + 2 * u;
  // The surface a ray leaves is handled by the rule above (never met again, or at its far
  // root), so the array's own cut-off only keeps roots at the origin from counting: 2(E + u).
  // The host, which traces an uncertain ray without that rule, skips four times the point's
  // error instead (HostOffset, from the error of the hit the ray leaves).
  // ε from the errors of certain hits at their best: a polygon's at its tightest rung (a root
  // nearer ε than its own error is flagged, never taken or dropped on a guess).
  double eEps = 0;
  for (const SphereTerms& t : p.spheres) eEps = std::max(eEps, t.tError);
  for (const ConeTerms& t : p.cones) eEps = std::max(eEps, t.tError);
  for (const PolygonTerms& t : p.polygons) eEps = std::max(eEps, t.tErrorRung[2]);
  p.epsilon = 2 * (eEps + u);
  p.error = Format::Unsigned(IntBitsFor(2 * (p.tError + u)) + 1, p.fracBits);
}

}  // namespace

SecondaryPlan PlanSecondary(const Scene& scene, int fracBits, double primaryTError) {
  if (fracBits < 8 || fracBits > 40)
    throw UserError("the secondary rays' fraction bits must be 8..40, got " +
                    std::to_string(fracBits));
  SecondaryPlan p;
  const SceneSurvey survey = Survey(scene, p);
  ChooseFormats(p, survey, fracBits, scene.objects.size());
  const double diameter = 2 * std::sqrt(3.0) * survey.extent;
  PlanPolygons(p, survey, diameter, fracBits);
  PlanObjects(scene, p, survey.extent, diameter, fracBits);
  p.primaryTError = primaryTError;
  PlanSlacks(p, diameter);
  for (const Light& l : scene.lights)
    for (int k = 0; k < 3; ++k) p.lights[k].push_back(Tight(l.position[k], fracBits));
  return p;
}

double HitError(const SecondaryPlan& plan, int bounce, int object, const Vec3& d) {
  if (bounce == 1)
    return plan.primaryErrors.empty() ? plan.primaryTError : plan.primaryErrors.at(size_t(object));
  const ObjectTerms& ob = plan.objects.at(size_t(object));
  if (ob.cone) return plan.cones[ob.index].tError;
  if (ob.sphere) return plan.spheres[ob.index].tError;
  const PolygonTerms& g = plan.polygons[ob.index];
  const Vec3 n{fixed::ToDouble(g.normal[0]), fixed::ToDouble(g.normal[1]),
               fixed::ToDouble(g.normal[2])};
  // The array chose its rung from its own n·d: any rung the true |n·d| reaches bounds the
  // error, and the host's n·d is within 2δ + 2^-F of the array's (both normalised).
  const double nd = std::abs(Dot(n, d)) - 2 * plan.directionError - 4 * plan.ulp;
  double e = g.tErrorRung[0];
  for (int k = 1; k < 3; ++k)
    if (nd >= kPolygonRungs[k]) e = g.tErrorRung[k];
  return e;
}

double HostOffset(const SecondaryPlan& plan, double hitError) {
  return 4 * (1.01 * hitError + plan.pointSlack);
}

namespace {

Multi Loaded(Machine& m, Format f, const std::vector<int64_t>& raw) {
  Multi x(m, f, "input");
  x.LoadRaw(raw);
  return x;
}

Multi Dot(const Multi (&a)[3], const Multi (&b)[3], Format out) {
  return Add(Add(Mul(a[0], b[0], out), Mul(a[1], b[1], out), out), Mul(a[2], b[2], out), out);
}

Multi Const(Machine& m, double x, int frac) { return Broadcast(m, Tight(x, frac)); }

// d·(1/|d|), floor-rounded at each step: |d| < 2 and 1/|d| below 2^inverseBits (1: the
// children of unit directions, |d| near 1; a normal whose length may be small takes more).
void Normalise(Multi (&d)[3], const SecondaryPlan& p, int inverseBits = 1) {
  const int F = p.fracBits;
  const Multi len = Sqrt(simd::SumOfSquares(d, Format::Unsigned(2, F)), Format::Unsigned(1, F));
  const Multi inv =
      Div(Uni{Fixed{Format::Unsigned(1, 0), 1}}, len, Format::Unsigned(inverseBits + 1, F));
  for (int k = 0; k < 3; ++k) d[k] = Mul(d[k], inv, p.direction);
}

// An ellipsoid's object-space ray o' = M(o − anchor), d' = M·d (EllipsoidTerms).
void ToObjectSpace(const Multi (&o)[3], const Multi (&d)[3], const EllipsoidTerms& e,
                   Multi (&ol)[3], Multi (&dl)[3]) {
  Multi rel[3];
  for (int k = 0; k < 3; ++k) rel[k] = Sub(o[k], Uni{e.anchor[k]}, e.offset);
  for (int k = 0; k < 3; ++k) {
    ol[k] = simd::Dot3(rel, e.inverse[k], e.local[k]);
    dl[k] = simd::Dot3(d, e.inverse[k], e.dLocal[k]);
  }
}

// One sphere along o + t·d: the two roots t0 <= t1 (meaningful where disc >= 0), the
// discriminant and whether it is within the grazing band.
struct Roots {
  Multi t0, t1, disc, grazing;
};

// |a × b|² with each component (in `cross`) clamped to the sphere's range first: only
// |a × b| <= r (times |d'| for an ellipsoid) can hit; larger saturate (a miss), expected.
Multi ClampedCrossSquared(Machine& m, const Multi (&a)[3], const Multi (&b)[3], Format cross,
                          const SphereTerms& s) {
  const Multi c[3] = {Sub(Mul(a[1], b[2], cross), Mul(a[2], b[1], cross), cross),
                      Sub(Mul(a[2], b[0], cross), Mul(a[0], b[2], cross), cross),
                      Sub(Mul(a[0], b[1], cross), Mul(a[1], b[0], cross), cross)};
  Multi sum;
  simd::WithExpectedSaturation(m, [&] {
    Multi sq[3];
    for (int k = 0; k < 3; ++k)
      sq[k] = Square(Convert(c[k], s.clamped, simd::kSaturate), s.square, simd::kSaturate);
    sum = Add(Add(sq[0], sq[1], s.square, simd::kSaturate), sq[2], s.square, simd::kSaturate);
  });
  return sum;
}

// An ellipsoid in its object space (the primary pass's ellipsoid program with o' a multi):
// f = −o', disc = r²|d'|² − |o'×d'|², roots (f·d' ∓ √disc)/|d'|².
Roots EllipsoidRoots(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const SphereTerms& s,
                     const SecondaryPlan& p) {
  const EllipsoidTerms& e = *s.ellipsoid;
  Multi ol[3], dl[3];
  ToObjectSpace(o, d, e, ol, dl);
  const Multi tcaN = Neg(Dot(ol, dl, e.products), e.products);
  const Multi sum = ClampedCrossSquared(m, ol, dl, e.products, s);
  const Multi dd = simd::SumOfSquares(dl, e.dd);
  Roots r;
  r.disc = Sub(Mul(dd, Uni{s.r2}, s.square), sum, s.disc);
  Multi root;
  simd::WithExpectedSaturation(m, [&] { root = Sqrt(r.disc, s.root); });  // a miss's: unused
  const Multi num0 = Sub(tcaN, root, e.numerator), num1 = Add(tcaN, root, e.numerator);
  simd::WithExpectedSaturation(m, [&] {
    r.t0 = Div(num0, dd, p.t, simd::kSaturate);
    r.t1 = Div(num1, dd, p.t, simd::kSaturate);
  });
  r.grazing = simd::Near(m, r.disc, s.grazeBand, e.fracBits);
  return r;
}

Roots SphereRoots(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const SphereTerms& s,
                  const SecondaryPlan& p) {
  if (s.ellipsoid) return EllipsoidRoots(m, o, d, s, p);
  Multi f[3];
  for (int k = 0; k < 3; ++k) f[k] = Sub(Uni{s.centre[k]}, o[k], p.offset);
  const Multi tca = Dot(d, f, p.t);
  const Multi sum = ClampedCrossSquared(m, f, d, p.t, s);
  Roots r;
  r.disc = Sub(Uni{s.r2}, sum, s.disc);
  Multi root;
  simd::WithExpectedSaturation(m, [&] { root = Sqrt(r.disc, s.root); });  // a miss's: unused
  r.t0 = Sub(tca, root, p.t);
  r.t1 = Add(tca, root, p.t);
  r.grazing = simd::Near(m, r.disc, s.grazeBand, p.fracBits);
  return r;
}

// A cone along o + t·d (ConeTerms): per root r (0: −sgn(β)·Q/A, 1: −sgn(β)·C/Q) its t, whether
// it is certainly a hit root (real, not grazing, its division certified and within range,
// its height certainly in [0, h]) and whether it may be one (not certainly a miss, beyond
// the scene, behind ε or out of height); `low`, a lower bound on the true t of a root that
// may be one (the format's least value where none is known); `larger` where root r is the
// larger of the two. A grazing root's bounds are the grazing divisions' (ConeTerms).
struct ConeCross {
  Multi t[2], ok[2], maybe[2], low[2], larger[2];
};

// A ray in a cone's local frame and its quadric A t² − 2β t + C (ConeAlong): every register
// lives until the roots are found, in the program's allocation order.
struct ConeQuadric {
  Multi rel[3], ol[3], dl[3];  // o − anchor; o and d in the local frame
  Multi rho, sdz;              // ρ = r0 + σ·o_z; σ·d_z
  Multi a, beta, cc, gx, gy, cross, disc;
  Multi grazing, real, possible;  // |disc| within the band; disc >= 0; either
  Multi root, q, negative;        // √disc; Q = |β| + √disc; β < 0
  Multi num[2];                   // the two roots' numerators (over A and over Q)
};

ConeQuadric ConeQuadricOf(Machine& m, const Multi (&o)[3], const Multi (&d)[3],
                          const ConeTerms& c) {
  const int Fl = c.fracBits;
  ConeQuadric k;
  for (int i = 0; i < 3; ++i) k.rel[i] = Sub(o[i], Uni{c.anchor[i]}, c.offset);
  for (int i = 0; i < 3; ++i) {
    k.ol[i] = simd::Dot3(k.rel, c.frame[i], c.local[i]);
    k.dl[i] = simd::Dot3(d, c.frame[i], c.dLocal[i]);
  }
  const Multi(&ol)[3] = k.ol;
  const Multi(&dl)[3] = k.dl;
  k.rho = Add(Mul(ol[2], Uni{c.sigma}, c.rho), Uni{c.r0}, c.rho);
  k.sdz = Mul(dl[2], Uni{c.sigma}, c.sigmaDz);
  k.a = Sub(Add(Square(dl[0], c.a), Square(dl[1], c.a), c.a), Square(k.sdz, c.a), c.a);
  k.beta = Sub(Add(Mul(ol[0], dl[0], c.beta), Mul(ol[1], dl[1], c.beta), c.beta),
               Mul(k.rho, k.sdz, c.beta), c.beta);
  k.cc = Sub(Add(Square(ol[0], c.c), Square(ol[1], c.c), c.c), Square(k.rho, c.c), c.c);
  k.gx = Sub(Mul(k.rho, dl[0], c.g), Mul(k.sdz, ol[0], c.g), c.g);
  k.gy = Sub(Mul(k.rho, dl[1], c.g), Mul(k.sdz, ol[1], c.g), c.g);
  k.cross = Sub(Mul(dl[0], ol[1], c.cross), Mul(dl[1], ol[0], c.cross), c.cross);
  k.disc = Sub(Add(Square(k.gx, c.square), Square(k.gy, c.square), c.square),
               Square(k.cross, c.square), c.disc);
  k.grazing = simd::Near(m, k.disc, c.grazeBand, Fl);
  k.real = simd::Zero(m) <= k.disc;
  k.possible = k.real || k.grazing;
  simd::WithExpectedSaturation(m, [&] { k.root = Sqrt(k.disc, c.root); });  // a miss's: unused
  k.q = Add(Abs(k.beta, c.q), k.root, c.q);
  k.negative = k.beta < simd::Zero(m);  // −sgn(β) = +1
  const Format signedQ = Format::Signed(c.q.intBits, Fl);
  // One full expression, as the two temporaries' lifetimes set the allocation order.
  Multi num[2] = {Select(k.negative, k.q, Neg(k.q, signedQ), signedQ),
                  Select(k.negative, k.cc, Neg(k.cc, c.c), c.c)};
  k.num[0] = std::move(num[0]), k.num[1] = std::move(num[1]);
  return k;
}

// Root r (0: num/A, 1: C/Q) of the quadric into x: its t where the division is certified,
// whether it is certainly a hit within the cone's height (ok), whether it may be one (maybe),
// and the least t it may have (low).
void ConeRoot(Machine& m, const ConeQuadric& k, const ConeTerms& c, const SecondaryPlan& p,
              int r, ConeCross& x) {
  const int Fl = c.fracBits;
  const Multi* den[2] = {&k.a, &k.q};
  const simd::ConeDivision* div[2][2] = {{&c.divA, &c.divAGrazing}, {&c.divC, &c.divCGrazing}};
  const Fixed tMax{p.t, p.t.MaxRaw()};
  const double h = fixed::ToDouble(c.height);
  // The quotient where the non-grazing division is certified (the grazing one's threshold
  // is higher: its numerator's error is larger).
  const Multi sure = !simd::Near(m, *den[r], div[r][0]->dStar, Fl);
  x.t[r] = Broadcast(m, tMax);
  Where(sure, [&] {
    simd::WithExpectedSaturation(m, [&] { x.t[r] = Div(k.num[r], *den[r], p.t, simd::kSaturate); });
  });
  Multi height;
  simd::WithExpectedSaturation(m, [&] {
    height = Add(k.ol[2], Mul(x.t[r], k.dl[2], c.s, simd::kSaturate), c.s, simd::kSaturate);
  });
  Multi inRange[2], inside[2], maybe[2], low[2];
  for (int g = 0; g < 2; ++g) {  // g = 1: the grazing bounds
    const simd::ConeDivision& v = *div[r][g];
    const double eT = v.tError, eH = c.heightError[g][r];
    const Multi certified = g ? !simd::Near(m, *den[r], v.dStar, Fl) : sure;
    // Beyond the scene: a certified quotient at or past tCut, or an uncertified one whose
    // |N|/(D* + eD) already exceeds tFar (|D| < D*: |t_exact| >= (|N| − eN)/(D* + eD)).
    const Multi beyond =
        (certified && !simd::Near(m, x.t[r], v.tCut, p.fracBits)) ||
        (!certified && !simd::Near(m, k.num[r], c.tFar * (v.dStar + v.eD) + v.eN, Fl));
    inRange[g] = certified && !beyond;
    inside[g] = (Const(m, eH, Fl) < height) && (height < Const(m, h - eH, Fl));
    const Multi outside = (height < Const(m, -eH, Fl)) || (Const(m, h + eH, Fl) < height);
    const Multi behind = x.t[r] < Const(m, p.epsilon - eT - p.ulp, p.fracBits);
    maybe[g] = !beyond && !(inRange[g] && (outside || behind));
    simd::WithExpectedSaturation(m, [&] {
      low[g] = Select(inRange[g], simd::SubBound(m, x.t[r], eT + p.ulp, p.t),
                      Broadcast(m, Fixed{p.t, p.t.MinRaw()}), p.t);
    });
  }
  x.ok[r] = k.real && !k.grazing && inRange[0] && inside[0];
  x.maybe[r] = k.possible && ((k.grazing && maybe[1]) || (!k.grazing && maybe[0]));
  x.low[r] = Select(k.grazing, low[1], low[0], p.t);
}

ConeCross ConeAlong(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const ConeTerms& c,
                    const SecondaryPlan& p) {
  const ConeQuadric k = ConeQuadricOf(m, o, d, c);
  ConeCross x;
  for (int r = 0; r < 2; ++r) ConeRoot(m, k, c, p, r, x);
  x.larger[0] = x.t[1] <= x.t[0];
  x.larger[1] = !x.larger[0];
  return x;
}

// A patch's normal at P (PolygonTerms::fan): the first fan triangle whose barycentric weights
// are all >= −1e-4 (the tracer's NormalAt) interpolates the vertex normals; none keeps the
// flat normal.
void PatchNormal(Machine& m, const Multi (&pt)[3], const PolygonTerms& g, const SecondaryPlan& p,
                 Multi (&normal)[3]) {
  const int F = p.fracBits;
  Multi rel[3];
  for (int k = 0; k < 3; ++k) rel[k] = Sub(pt[k], Uni{g.vertices[0][k]}, p.edgeVector);
  const Multi low = Const(m, -1e-4, F), one = Const(m, 1, F);
  Multi found = simd::Zero(m);
  for (const PolygonTerms::FanTriangle& f : g.fan) {
    const Multi v = simd::Dot3(rel, f.alpha, g.weight), w = simd::Dot3(rel, f.beta, g.weight);
    const Multi uw = Sub(Sub(one, v, g.weight), w, g.weight);
    const Multi here = !found && (low <= uw) && (low <= v) && (low <= w);
    Where(here, [&] {
      const auto& a = g.vertexNormals[0];
      const auto& b = g.vertexNormals[f.i];
      const auto& c = g.vertexNormals[f.i + 1];
      for (int k = 0; k < 3; ++k)
        normal[k] =
            Add(Add(Mul(uw, Uni{a[k]}, p.direction, simd::kSaturate),
                    Mul(v, Uni{b[k]}, p.direction, simd::kSaturate), p.direction, simd::kSaturate),
                Mul(w, Uni{c[k]}, p.direction, simd::kSaturate), p.direction, simd::kSaturate);
    });
    found = found || here;
  }
}

// One polygon along o + t·d: t (where |n·d| is not within the parallel band), whether the ray
// certainly passes inside, whether it might (the edge functions and the facing as the
// tracer's InsideAlongRay, each edge certain beyond ±edgeBand), and `parallel` (|n·d| small:
// t not computed, not certified).
struct PolygonCross {
  Multi t, inside, possible, parallel;
  Multi err;  // |t − t_exact| + ulp where certified: the tightest rung |n·d| reaches
};

PolygonCross PolygonAlong(Machine& m, const Multi (&o)[3], const Multi (&d)[3],
                          const PolygonTerms& g, const SecondaryPlan& p) {
  const int F = p.fracBits;
  const Format wide = Format::Signed(p.intBits + 3, F);
  const Multi nd = simd::Dot3(d, g.normal, wide), no = simd::Dot3(o, g.normal, wide);
  const Multi num = Sub(Uni{g.offset}, no, wide);
  PolygonCross c;
  c.parallel = simd::Near(m, nd, p.parallelBand, F);
  c.err = Convert(Const(m, g.tErrorRung[0] + p.ulp, F), p.error);
  for (int k = 1; k < 3; ++k) {
    const Multi tighter = !simd::Near(m, nd, kPolygonRungs[k], F);
    Where(tighter, [&] { c.err = Const(m, g.tErrorRung[k] + p.ulp, F); });
  }
  c.t = Broadcast(m, Fixed{p.t, p.t.MaxRaw()});
  Where(!c.parallel, [&] {
    simd::WithExpectedSaturation(m, [&] { c.t = Div(num, nd, p.t, simd::kSaturate); });
  });
  const Multi facing = simd::Zero(m) < nd;  // s = sign(d·n) > 0
  std::vector<std::array<Multi, 3>> rel(g.vertices.size());
  for (size_t v = 0; v < g.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) rel[v][k] = Sub(Uni{g.vertices[v][k]}, o[k], p.edgeVector);
  const Multi band = Const(m, g.edgeBand, F), minusBand = Const(m, -g.edgeBand, F);
  Multi inside = simd::Zero(m), unsure = simd::Zero(m);
  for (const PolygonEdgeGroup& group : g.groups) {
    Multi in = Broadcast(m, Fixed{bitserial::BoolFormat(), 1}), out = simd::Zero(m);
    for (const PolygonEdge& e : group) {
      const auto& pa = rel[e.p];
      const auto& qa = rel[e.q];
      const Multi cross[3] = {
          Sub(Mul(pa[1], qa[2], p.edgeCross), Mul(pa[2], qa[1], p.edgeCross), p.edgeCross),
          Sub(Mul(pa[2], qa[0], p.edgeCross), Mul(pa[0], qa[2], p.edgeCross), p.edgeCross),
          Sub(Mul(pa[0], qa[1], p.edgeCross), Mul(pa[1], qa[0], p.edgeCross), p.edgeCross)};
      const Multi value = Dot(d, cross, p.edgeValue);
      // side·s·e > 0 is the inside: with side < 0 the comparisons swap.
      const Multi above = band < value, below = value < minusBand;
      const Multi& pos = e.side > 0 ? above : below;
      const Multi& neg = e.side > 0 ? below : above;
      in = in && ((facing && pos) || (!facing && neg));
      out = out || (facing && neg) || (!facing && pos);
    }
    unsure = unsure || (!in && !out);
    inside = Xor(inside, in);
  }
  c.possible = inside || unsure;
  c.inside = inside && !unsure && !c.parallel;
  return c;
}

// The first sphere along every ray: object (index + 1, 0 = none), t, and whether that is
// uncertain (a grazing or near-ε candidate that may lie in front, or two hits within their
// bounds of each other).
struct Nearest {
  Multi object, t, uncertain;
};

// The search for each ray's nearest hit, object by object (FindNearest): the best so far
// (n: object index + 1 and t; bestErr: its t error + ulp), whether a candidate tied with it,
// and the nearest t at which an uncertain candidate may lie (tGraze). Made by Start, in the
// program's allocation order.
struct NearestSearch {
  Machine& m;
  const SecondaryPlan& p;
  Nearest n;
  Multi tie, tGraze, eps, none, bestErr;

  static NearestSearch Start(Machine& m, const SecondaryPlan& p) {
    const Fixed tMax{p.t, p.t.MaxRaw()};
    NearestSearch s{m, p, {}, {}, {}, {}, {}, {}};
    s.n.t = Broadcast(m, tMax);
    s.n.object = Broadcast(m, Fixed{p.index, 0});
    s.tie = simd::Zero(m), s.tGraze = Broadcast(m, tMax);
    s.eps = Const(m, p.epsilon, p.fracBits), s.none = Broadcast(m, tMax);
    s.bestErr = Broadcast(m, Fixed{p.error, 0});
    return s;
  }
  // Object i's candidate t where `hit` into the best, with its error `err`: a tie with the
  // best (their t within the sum of their errors) flagged.
  void Fold(const Multi& t, const Multi& hit, size_t i, const Multi& err) {
    Multi band;
    simd::WithExpectedSaturation(m, [&] { band = Add(err, bestErr, p.error, simd::kSaturate); });
    tie = tie || (hit && (n.t < none) && simd::Near(m, t - n.t, band, p.fracBits));
    const Multi closer = hit && (t < n.t);
    Where(closer, [&] {
      n.t = t;
      n.object = Broadcast(m, Fixed{p.index, int64_t(i) + 1});
      bestErr = err;
    });
  }
  // An uncertain candidate at or beyond `low` where `unsure`.
  void Graze(const Multi& unsure, const Multi& low) {
    Where(unsure, [&] { tGraze = Min(tGraze, low, p.t); });
  }
  Multi ErrOf(double e) const { return Const(m, e + p.ulp, p.fracBits); }
};

// Convex (a frustum): a ray leaving the cone outward never meets it again; one entering it
// meets it at its larger root, if that lies in [0, h] (else it leaves by an open end).
void ConeCandidates(NearestSearch& s, const Multi (&o)[3], const Multi (&d)[3], const Multi& self,
                    const Multi& outward, size_t i) {
  const SecondaryPlan& p = s.p;
  const ConeTerms& c = p.cones[p.objects[i].index];
  const ConeCross x = ConeAlong(s.m, o, d, c, p);
  const Multi leaving = self && outward, entering = self && !outward;
  for (int r = 0; r < 2; ++r) {
    const Multi consider = !leaving && (!entering || x.larger[r]);
    const Multi nearEps =
        x.ok[r] && !self && simd::Near(s.m, x.t[r] - s.eps, c.tError + p.ulp, p.fracBits);
    const Multi unsure = !leaving && ((x.maybe[r] && !x.ok[r]) || (consider && nearEps));
    s.Graze(unsure, x.low[r]);
    s.Fold(x.t[r], consider && x.ok[r] && (s.eps < x.t[r]), i, s.ErrOf(c.tError));
  }
}

// A plane is met once: the polygon a ray leaves is never its next hit.
void PolygonCandidate(NearestSearch& s, const Multi (&o)[3], const Multi (&d)[3],
                      const Multi& self, size_t i) {
  const SecondaryPlan& p = s.p;
  Machine& m = s.m;
  const PolygonTerms& g = p.polygons[p.objects[i].index];
  const PolygonCross c = PolygonAlong(m, o, d, g, p);
  const Multi hit = c.inside && (s.eps < c.t) && !self;
  const Multi front =
      c.parallel || (Const(m, p.epsilon - g.tError - p.ulp, p.fracBits) < c.t);
  const Multi unsure =
      c.possible && !self && front && (!c.inside || simd::Near(m, c.t - s.eps, c.err, p.fracBits));
  Multi low;
  simd::WithExpectedSaturation(m, [&] {
    low = Select(c.parallel, Broadcast(m, Fixed{p.t, p.t.MinRaw()}),
                 Sub(c.t, c.err, p.t, simd::kSaturate), p.t);
  });
  s.Graze(unsure, low);
  s.Fold(c.t, hit, i, c.err);
}

// The sphere the ray leaves: outward, no hit; inward, its far root.
void SphereCandidate(NearestSearch& s, const Multi (&o)[3], const Multi (&d)[3], const Multi& self,
                     const Multi& outward, size_t i) {
  const SecondaryPlan& p = s.p;
  Machine& m = s.m;
  const int F = p.fracBits;
  const SphereTerms& sp = p.spheres[p.objects[i].index];
  const Roots r = SphereRoots(m, o, d, sp, p);
  const Multi leaving = self && outward, entering = self && !outward;
  const Multi t =
      Select(entering || (s.eps < r.t0), Select(entering, r.t1, r.t0, p.t), r.t1, p.t);
  const Multi real = simd::Zero(m) <= r.disc;
  const Multi hit = real && (s.eps < t) && !leaving;
  // Uncertain: grazing, or a root within its bound of ε — unless the far root is
  // certainly behind ε; on the sphere it enters, only grazing.
  const Multi nearEps = (simd::Near(m, r.t0 - s.eps, sp.tError + p.ulp, F) ||
                         simd::Near(m, r.t1 - s.eps, sp.tError + p.ulp, F)) &&
                        (real || r.grazing) && !self;
  const Multi front = Const(m, p.epsilon - sp.slack, F) < r.t1;
  const Multi unsure = (r.grazing || nearEps) && front && !leaving;
  Where(unsure, [&] { s.tGraze = Min(s.tGraze, simd::SubBound(m, r.t0, sp.slack, p.t), p.t); });
  s.Fold(t, hit, i, s.ErrOf(sp.tError));
}

Nearest FindNearest(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const Multi& from,
                    const Multi& outward, const SecondaryPlan& p) {
  NearestSearch s = NearestSearch::Start(m, p);
  for (size_t i = 0; i < p.objects.size(); ++i) {
    const Multi self = from == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
    if (p.objects[i].cone)
      ConeCandidates(s, o, d, self, outward, i);
    else if (!p.objects[i].sphere)
      PolygonCandidate(s, o, d, self, i);
    else
      SphereCandidate(s, o, d, self, outward, i);
  }
  // A flagged candidate matters if it may lie in front of the best's true t <= t + E.
  Multi limit;
  simd::WithExpectedSaturation(m, [&] { limit = Add(s.n.t, s.bestErr, p.t, simd::kSaturate); });
  s.n.uncertain = s.tie || ((s.tGraze <= limit) && (s.tGraze < s.none));
  return std::move(s.n);
}

// One light's shadow rays, object by object (ShadowProduct): the product S of the
// transparencies crossed before the light (`through`) and whether some crossing is uncertain.
struct ShadowRays {
  Machine& m;
  const SecondaryPlan& p;
  const Multi& dist;  // to the light
  Multi& through;
  Multi& uncertain;
  Multi eps, zero;
  // S times the transparency of the object crossed where `cross` (0 for an opaque one).
  void Cross(const Multi& cross, double transparency) {
    if (transparency <= 0) {
      Where(cross, [&] { through = zero; });
    } else {
      const Uni kt{Tight(transparency, p.fracBits)};
      Where(cross, [&] { through = Mul(through, kt, p.unit); });
    }
  }
};

// From the outside of its own cone a shadow ray never meets it again; from the inside it
// crosses it at its larger root if that lies in [0, h] (else it leaves by an open end).
void ConeShadow(ShadowRays& s, const Multi (&pt)[3], const Multi (&l)[3], const Multi& self,
                const Multi& inside, size_t i) {
  const SecondaryPlan& p = s.p;
  const int F = p.fracBits;
  const ConeTerms& c = p.cones[p.objects[i].index];
  const ConeCross x = ConeAlong(s.m, pt, l, c, p);
  const Multi skip = self && !inside, fromInside = self && inside;
  const double band = c.tError + p.ulp;
  for (int r = 0; r < 2; ++r) {
    const Multi consider = !skip && (!fromInside || x.larger[r]);
    const Multi cross = consider && x.ok[r] && (s.eps < x.t[r]) && (x.t[r] < s.dist);
    s.Cross(cross, c.transparency);
    const Multi near = (!self && simd::Near(s.m, x.t[r] - s.eps, band, F)) ||
                       simd::Near(s.m, x.t[r] - s.dist, band, F);
    const Multi past = s.dist < x.low[r];  // certainly beyond the light
    s.uncertain = s.uncertain ||
                  (!skip && ((x.maybe[r] && !x.ok[r] && !past) || (consider && x.ok[r] && near)));
  }
}

void PolygonShadow(ShadowRays& s, const Multi (&pt)[3], const Multi (&l)[3], const Multi& self,
                   size_t i) {
  const SecondaryPlan& p = s.p;
  Machine& m = s.m;
  const int F = p.fracBits;
  const PolygonTerms& g = p.polygons[p.objects[i].index];
  const PolygonCross c = PolygonAlong(m, pt, l, g, p);
  const Multi cross = c.inside && (s.eps < c.t) && (c.t < s.dist) && !self;
  s.Cross(cross, g.transparency);
  const double band = g.tError + p.ulp;
  const Multi inRange = c.parallel || ((Const(m, p.epsilon - band, F) < c.t) &&
                                       (simd::SubBound(m, c.t, band, p.t) < s.dist));
  const Multi near =
      simd::Near(m, c.t - s.eps, c.err, F) || simd::Near(m, c.t - s.dist, c.err, F);
  s.uncertain = s.uncertain || (c.possible && !self && inRange && (!c.inside || near));
}

// The hit's own sphere (`self`): a shadow ray from outside (`inside` 0) cannot meet it
// again; from inside it crosses it once, at the far root, when the light is outside it.
void SphereShadow(ShadowRays& s, const Multi (&pt)[3], const Multi (&l)[3], const Multi& self,
                  const Multi& inside, size_t i, size_t light) {
  const SecondaryPlan& p = s.p;
  Machine& m = s.m;
  const int F = p.fracBits;
  const SphereTerms& sp = p.spheres[p.objects[i].index];
  const Roots r = SphereRoots(m, pt, l, sp, p);
  const Multi real = simd::Zero(m) <= r.disc;
  const Multi cross0 = real && (s.eps < r.t0) && (r.t0 < s.dist) && !self;
  const Multi exits =
      inside && Broadcast(m, Fixed{bitserial::BoolFormat(), sp.lightOutside[light] ? 1 : 0});
  const Multi cross1 = (real && (s.eps < r.t1) && (r.t1 < s.dist) && !self) || (self && exits);
  if (sp.transparency <= 0) {
    s.Cross(cross0 || cross1, sp.transparency);
  } else {
    s.Cross(cross0, sp.transparency);
    s.Cross(cross1, sp.transparency);
  }
  const double band = sp.tError + p.ulp;
  const Multi near =
      simd::Near(m, r.t0 - s.eps, band, F) || simd::Near(m, r.t1 - s.eps, band, F) ||
      simd::Near(m, r.t0 - s.dist, band, F) || simd::Near(m, r.t1 - s.dist, band, F);
  const Multi inRange = (Const(m, p.epsilon - sp.slack, F) < r.t1) &&
                        (simd::SubBound(m, r.t0, sp.slack, p.t) < s.dist);
  const Multi unsure = (r.grazing || (near && (real || r.grazing) && !self)) && inRange;
  s.uncertain = s.uncertain || (unsure && !self);
}

// The light let through toward one light from every hit point P along the unit l (distance
// dist): each root in (ε, dist) multiplies by its object's T; `uncertain` where a root or the
// grazing band is within its bound of deciding a crossing. `object` is the hit's (index + 1).
void ShadowProduct(Machine& m, const Multi (&pt)[3], const Multi (&l)[3], const Multi& dist,
                   const Multi& object, const Multi& inside, const SecondaryPlan& p, size_t light,
                   Multi& through, Multi& uncertain) {
  const int F = p.fracBits;
  through = Broadcast(m, Fixed{p.unit, int64_t(1) << F});
  uncertain = simd::Zero(m);
  ShadowRays s{m, p, dist, through, uncertain, Const(m, p.epsilon, F),
               Broadcast(m, Fixed{p.unit, 0})};
  for (size_t i = 0; i < p.objects.size(); ++i) {
    const Multi self = object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
    if (p.objects[i].cone)
      ConeShadow(s, pt, l, self, inside, i);
    else if (!p.objects[i].sphere)
      PolygonShadow(s, pt, l, self, i);
    else
      SphereShadow(s, pt, l, self, inside, i, light);
  }
}

// What one bounce's program holds on the array from stage to stage (Run). Each register is
// allocated where the program first computes it (allocation is first fit in program order:
// BounceFits), and lives until the program ends.
struct BounceRegisters {
  Multi o[3], d[3];          // the rays: origin, unit direction
  Multi live, outward;       // a ray in the slot; it leaves its object outward
  Multi from;                // the object it leaves (index + 1; 0: the eye)
  Multi object, t;           // its nearest hit (index + 1; 0: none) and distance
  Multi uncertain;           // the hit is not certain (the host traces the ray)
  Multi hit;                 // live and a hit
  Multi pt[3], normal[3];    // the hit point; the unit normal facing the ray
  Multi inside;              // the ray meets its object from inside
  Multi mirror[3], refracted[3], tir;  // the children's directions; total internal reflection
  std::vector<Multi> nl, rv, through, shadowUnsure;  // per light: N·L, R·(−D), S, S uncertain
};

// The rays as the previous bounce or the primary pass left them (bounce 1 also its hits).
void LoadRays(Machine& m, const SecondaryPlan& p, bool intersect, const BounceInputs& in,
              BounceRegisters& r) {
  for (int k = 0; k < 3; ++k)
    r.o[k] = Loaded(m, p.coord, in.o[k]), r.d[k] = Loaded(m, p.direction, in.d[k]);
  auto flags = [&](const std::vector<uint8_t>& v) {
    return Loaded(m, bitserial::BoolFormat(), std::vector<int64_t>(v.begin(), v.end()));
  };
  r.live = flags(in.live), r.outward = flags(in.outward);
  r.from = Loaded(m, p.index, in.from);
  if (!intersect) r.object = Loaded(m, p.index, in.object), r.t = Loaded(m, p.t, in.t);
}

// Each ray's nearest object (bounce 1: the primary pass's, certain).
void FindHits(Machine& m, const SecondaryPlan& p, bool intersect, BounceRegisters& r) {
  if (intersect) {
    bitserial::WhereScope scope(r.live);
    Normalise(r.d, p);
    Nearest n = FindNearest(m, r.o, r.d, r.from, r.outward, p);
    r.object = std::move(n.object), r.t = std::move(n.t), r.uncertain = std::move(n.uncertain);
  } else {
    r.uncertain = simd::Zero(m);
  }
  r.hit = r.live && (Broadcast(m, Fixed{p.index, 0}) < r.object);
}

// The normal of object i at the hit points of the rays that hit it, into `normal`.
void ObjectNormal(Machine& m, const SecondaryPlan& p, size_t i, const Multi (&pt)[3],
                  Multi (&normal)[3]) {
  if (p.objects[i].cone) {  // frameᵀ·(x_L, y_L, −σρ): the radial direction tilted by σ
    const ConeTerms& c = p.cones[p.objects[i].index];
    Multi rel[3], ol[3];
    for (int k = 0; k < 3; ++k) rel[k] = Sub(pt[k], Uni{c.anchor[k]}, c.offset);
    for (int k = 0; k < 3; ++k) ol[k] = simd::Dot3(rel, c.frame[k], c.local[k]);
    const Multi rho = Add(Mul(ol[2], Uni{c.sigma}, c.rho), Uni{c.r0}, c.rho);
    ol[2] = Neg(Mul(rho, Uni{c.sigma}, c.rho), c.rho);
    for (int k = 0; k < 3; ++k) {
      const Fixed column[3] = {c.normalScale[0][k], c.normalScale[1][k], c.normalScale[2][k]};
      normal[k] = simd::Dot3(ol, column, p.direction);
    }
    return;
  }
  if (!p.objects[i].sphere) {  // the polygon's front normal, or a patch's interpolated one
    const PolygonTerms& g = p.polygons[p.objects[i].index];
    for (int k = 0; k < 3; ++k) normal[k] = Broadcast(m, g.normal[k]);
    if (!g.fan.empty()) PatchNormal(m, pt, g, p, normal);
    return;
  }
  const SphereTerms& s = p.spheres[p.objects[i].index];
  if (s.ellipsoid) {  // Mᵀ·M(P − anchor): the object-space normal mapped to world space
    const EllipsoidTerms& e = *s.ellipsoid;
    Multi rel[3], ol[3];
    for (int k = 0; k < 3; ++k) rel[k] = Sub(pt[k], Uni{e.anchor[k]}, e.offset);
    for (int k = 0; k < 3; ++k) ol[k] = simd::Dot3(rel, e.inverse[k], e.local[k]);
    for (int k = 0; k < 3; ++k) {
      const Fixed column[3] = {s.normalScale[0][k], s.normalScale[1][k], s.normalScale[2][k]};
      normal[k] = simd::Dot3(ol, column, p.direction);
    }
    return;
  }
  for (int k = 0; k < 3; ++k)
    normal[k] = Mul(Sub(pt[k], Uni{s.centre[k]}, p.offset), Uni{s.inverseRadius}, p.direction,
                    simd::kSaturate);
}

// The hit point P = o + t d and the unit normal there (P − c)/r of the sphere hit (or its
// kind's), normalised.
void SurfaceNormals(Machine& m, const SecondaryPlan& p, BounceRegisters& r) {
  for (int k = 0; k < 3; ++k) r.pt[k] = Add(r.o[k], Mul(r.t, r.d[k], p.t), p.coord);
  for (int k = 0; k < 3; ++k) r.normal[k] = Multi(m, p.direction, "normal");
  for (size_t i = 0; i < p.objects.size(); ++i) {
    bitserial::WhereScope one(r.object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1}));
    ObjectNormal(m, p, i, r.pt, r.normal);
  }
  Normalise(r.normal, p, p.normalInverseBits);
}

// The transmitted direction (Snell; hosts/trace/tracer.h Refract): eta = ior leaving, 1/ior
// entering; under total internal reflection the mirror direction.
void Refractions(Machine& m, const SecondaryPlan& p, BounceRegisters& r, const Multi& dn) {
  const int F = p.fracBits;
  Multi eta = Const(m, 1, F);
  for (size_t i = 0; i < p.objects.size(); ++i) {
    const ObjectTerms& ob = p.objects[i];
    const double t = ob.cone     ? p.cones[ob.index].transparency
                     : ob.sphere ? p.spheres[ob.index].transparency
                                 : p.polygons[ob.index].transparency;
    const double ior = ob.cone     ? p.cones[ob.index].ior
                       : ob.sphere ? p.spheres[ob.index].ior
                                   : p.polygons[ob.index].ior;
    if (t <= 0) continue;
    const Multi one = r.object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
    Where(one && r.inside, [&] { eta = Const(m, ior, F); });
    Where(one && !r.inside, [&] { eta = Const(m, 1 / ior, F); });
  }
  const Multi cosi = Neg(dn, Format::Signed(2, F));
  const Multi sin2 =
      Sub(Const(m, 1, F), Square(cosi, Format::Unsigned(2, F)), Format::Signed(2, F));
  const Format wide = Format::Signed(2 * p.eta.intBits + 2, F);
  const Multi k = Sub(Const(m, 1, F), Mul(Square(eta, wide), sin2, wide), wide);
  r.tir = k < simd::Zero(m);
  Multi root;
  simd::WithExpectedSaturation(
      m, [&] { root = Sqrt(k, Format::Unsigned(2 * p.eta.intBits + 2, F)); });
  const Format term = Format::Signed(p.eta.intBits + 2, F);
  const Multi coef = Sub(Mul(eta, cosi, term), root, term);
  for (int c = 0; c < 3; ++c)
    r.refracted[c] =
        Add(Mul(eta, r.d[c], term), Mul(coef, r.normal[c], term), p.direction, simd::kSaturate);
  for (int c = 0; c < 3; ++c) Where(r.tir, [&] { r.refracted[c] = r.mirror[c]; });
  Normalise(r.refracted, p);
}

// Each light: the unit direction l, N·L, R·(−D) = l·d − 2(N·L)(N·d), the shadow product.
void LightTerms(Machine& m, const SecondaryPlan& p, BounceRegisters& r, const Multi& dn) {
  const int F = p.fracBits;
  for (size_t j = 0; j < r.nl.size(); ++j) {
    Multi w[3], l[3];
    for (int k = 0; k < 3; ++k) w[k] = Sub(Uni{p.lights[k][j]}, r.pt[k], p.toLight);
    const Multi dist =
        Sqrt(simd::SumOfSquares(w, Format::Unsigned(2 * p.toLight.intBits, F)), p.distance);
    for (int k = 0; k < 3; ++k) l[k] = Div(w[k], dist, p.direction, simd::kSaturate);
    r.nl[j] = Dot(r.normal, l, p.direction);
    const Multi twice = Mul(r.nl[j], dn, p.direction);
    r.rv[j] = Sub(Dot(l, r.d, p.direction), Add(twice, twice, Format::Signed(2, F)),
                  Format::Signed(3, F), simd::kSaturate);
    ShadowProduct(m, r.pt, l, dist, r.object, r.inside, p, j, r.through[j], r.shadowUnsure[j]);
  }
}

// Where a ray hit: the normal faced toward it, the children's directions, each light's terms.
void ShadeHits(Machine& m, const SecondaryPlan& p, BounceRegisters& r) {
  bitserial::WhereScope scope(r.hit);
  SurfaceNormals(m, p, r);
  Multi dn = Dot(r.d, r.normal, p.direction);
  r.inside = simd::Zero(m) < dn;
  Where(r.inside, [&] {
    for (int k = 0; k < 3; ++k) r.normal[k] = Neg(r.normal[k], p.direction);
    dn = Neg(dn, p.direction);
  });
  for (int k = 0; k < 3; ++k) {
    const Multi twice = Mul(dn, r.normal[k], p.t);
    r.mirror[k] = Sub(r.d[k], Add(twice, twice, p.t), p.direction, simd::kSaturate);
  }
  if (p.anyTransparent) Refractions(m, p, r, dn);
  LightTerms(m, p, r, dn);
}

// x's raw values read over the host link (charged by the caller's count of bits).
void ReadOver(const Multi& x, std::vector<int64_t>& to, BounceOutputs& out) {
  to = x.ReadRaw();
  out.hostLinkBits += int64_t(x.Width()) * x.GetMachine().VirtualPes();
}
void ReadFlagsOver(const Multi& x, std::vector<uint8_t>& to, BounceOutputs& out) {
  std::vector<int64_t> raw;
  ReadOver(x, raw, out);
  to.assign(raw.begin(), raw.end());
}
// The emulation's copy of what stays on the array (not charged: the next bounce reads it
// where it is).
void Peek(const Multi& x, std::vector<int64_t>& to) {
  const int w = x.Width();
  const int64_t n = x.GetMachine().VirtualPes();
  to.assign(n, 0);
  for (int i = 0; i < w; ++i)
    for (int64_t pe = 0; pe < n; ++pe)
      if (x.BitAt(i, pe)) to[pe] |= int64_t{1} << i;
  if (x.Format().isSigned)
    for (int64_t& v : to)
      if ((v >> (w - 1)) & 1) v -= int64_t{1} << w;
}

// The records the host reads (BounceOutputs); overflow anywhere in a ray's program (its
// flags latch per PE) makes it uncertain.
void ReadRecords(Machine& m, const SecondaryPlan& p, const BounceInputs& in,
                 const BounceRegisters& r, BounceOutputs& out, bool audit) {
  const int64_t n = m.VirtualPes();
  const size_t lights = r.nl.size();
  ReadOver(r.object, out.object, out);
  m.Charge("hostRead", bitserial::HostTransferCost(1));  // the overflow flags
  ReadFlagsOver(r.uncertain, out.uncertain, out);
  for (int64_t pe = 0; pe < n; ++pe)
    if (m.Overflow(pe) || m.DivideByZero(pe)) out.uncertain[pe] = 1;
  ReadFlagsOver(r.tir, out.tir, out);
  out.nl.resize(lights), out.rv.resize(lights), out.through.resize(lights);
  out.shadowUncertain.resize(lights);
  bool anyShadowUnsure = false;
  for (size_t j = 0; j < lights; ++j) {
    ReadOver(r.nl[j], out.nl[j], out), ReadOver(r.rv[j], out.rv[j], out);
    ReadOver(r.through[j], out.through[j], out);
    ReadFlagsOver(r.shadowUnsure[j], out.shadowUncertain[j], out);
    anyShadowUnsure |= std::find(out.shadowUncertain[j].begin(), out.shadowUncertain[j].end(),
                                 1) != out.shadowUncertain[j].end();
  }
  bool anyUnsure = false;
  for (int64_t pe = 0; pe < n; ++pe) anyUnsure |= in.live[pe] && out.uncertain[pe];
  if (audit)
    for (int k = 0; k < 3; ++k) Peek(r.o[k], out.audit.o[k]), Peek(r.d[k], out.audit.d[k]);
  std::vector<int64_t> inside;
  Peek(r.inside, inside);
  out.inside.assign(inside.begin(), inside.end());
  for (int k = 0; k < 3; ++k) {
    if (anyUnsure) ReadOver(r.o[k], out.o[k], out), ReadOver(r.d[k], out.d[k], out);
    if (anyShadowUnsure)
      ReadOver(r.pt[k], out.p[k], out);
    else
      Peek(r.pt[k], out.p[k]);
    Peek(r.mirror[k], out.mirror[k]);
    if (p.anyTransparent) Peek(r.refracted[k], out.refracted[k]);
  }
}

// The whole program: the rays loaded, their hits, the shading terms at them, the records
// read; out = nullptr runs it for its allocation only (BounceFits).
void Run(Machine& m, const SecondaryPlan& p, bool intersect, const BounceInputs& in,
         BounceOutputs* out, bool audit) {
  BounceRegisters r;
  LoadRays(m, p, intersect, in, r);
  // The inputs are already on the array (the previous bounce or the primary pass wrote
  // them; the compaction's moves are charged apart): the program starts here.
  m.Report().Clear();
  m.ClearFlags();
  FindHits(m, p, intersect, r);
  r.tir = simd::Zero(m);
  const size_t lights = p.lights[0].size();
  r.nl.resize(lights), r.rv.resize(lights), r.through.resize(lights), r.shadowUnsure.resize(lights);
  ShadeHits(m, p, r);
  if (out) ReadRecords(m, p, in, r, *out, audit);
}

}  // namespace

void RunBounce(Machine& m, const SecondaryPlan& plan, bool intersect, const BounceInputs& in,
               BounceOutputs& out, bool audit) {
  Run(m, plan, intersect, in, &out, audit);
}

int64_t LightRecordBits(const SecondaryPlan& plan) {
  // The widths Run gives nl, rv, through and shadowUnsure.
  const int F = plan.fracBits;
  const int64_t each = int64_t(plan.direction.Width()) + Format::Signed(3, F).Width() +
                       plan.unit.Width() + 1;
  const auto lights = int64_t(plan.lights[0].size());
  return lights > INT64_MAX / each ? INT64_MAX : lights * each;
}

bool BounceFits(const bitserial::MachineProfile& profile, int layers, const SecondaryPlan& plan,
                bool intersect) {
  bitserial::MachineProfile one = profile;
  one.physicalPes = 512;
  one.shapes = {bitserial::MeshShape{{64, 8}}};
  one.internalBitsPerPe /= layers;
  one.externalBitsPerPe /= layers;
  BounceInputs in;
  for (int k = 0; k < 3; ++k) in.o[k].assign(1, 0), in.d[k].assign(1, 0);
  in.object.assign(1, 0), in.t.assign(1, 0), in.from.assign(1, 0);
  in.live.assign(1, 0), in.outward.assign(1, 0);
  try {
    Machine m(one, 1);
    Run(m, plan, intersect, in, nullptr, false);
    return true;
  } catch (const UserError&) {
    return false;
  }
}

}  // namespace zephyr::wavefront
