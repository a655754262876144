// The error bounds of the SIMD primary pass audited against the exact reference
// (docs/simd.md, "Error bounds", the audit table). For each primitive kind — sphere,
// ellipsoid, polygon, cone, cylinder — one-object scenes at several widths, and for each many
// directions drawn to stress the bounds: grazing rays at chosen discriminants (inside and on
// both sides of the grazing band G, just above every rung 4^j·G of a cone's ladder), rays near
// a cone's axis bisected to divisors just above every rung 4^k·D* (the small divisors), near a
// polygon's edges and across a polygon seen edge-on or from just above its plane (tiny
// denominators), far, tiny and huge objects, an eye inside a sphere and a cylinder, hither
// through a sphere; half of them moved within one direction ulp so that two components round
// by almost half an ulp (δ), with random signs. The rungs of the cones' ladders the views
// reach are printed (14 of Q/A's 16, 7 of C/Q's). Each object program runs on the emulated array
// with an Audit (hosts/simd/audit.h), which records every quantity it computes with the bound
// it claims at each PE; the test computes the same quantity exactly (128-bit, from the
// scene's doubles) and asserts |value − exact| <= bound at every PE where it is claimed. The
// tightness (largest actual / bound) is printed per kind and quantity and recorded
// (RecordProperty).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bitserial/machine.h"
#include "bitserial/multi.h"
#include "hosts/simd/audit.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/object.h"
#include "hosts/simd/plan.h"
#include "hosts/trace/exact.h"
#include "hosts/trace/intersect.h"

namespace zephyr::simd {
namespace {

using exact::Real;
using RVec = Vec3T<Real>;

// ---- the exact side ------------------------------------------------------------------

RVec R(const Vec3& v) { return {Real(v.x), Real(v.y), Real(v.z)}; }
Real Sqrt(const Real& x) { return sqrt(x); }
Real Norm(const RVec& v) { return Sqrt(Dot(v, v)); }
Real FromFixed(const fixed::Fixed& f) { return ldexp(Real(f.raw), -f.format.fracBits); }

// The world-to-object map as the scene computes it in double (its inverse), then exact.
struct ExactFrame {
  RVec row[3];
  RVec eye;  // the object-space eye
  RVec Apply(const RVec& d) const { return {Dot(row[0], d), Dot(row[1], d), Dot(row[2], d)}; }
};
ExactFrame FrameOf(const Primitive& p, const Vec3& eye) {
  const Affine inv = p.transform ? p.transform->Inverse() : Affine{};
  ExactFrame f;
  for (int r = 0; r < 3; ++r) f.row[r] = R({inv.m[r][0], inv.m[r][1], inv.m[r][2]});
  const RVec e = R(eye);
  f.eye = f.Apply(e) + R({inv.m[0][3], inv.m[1][3], inv.m[2][3]});
  return f;
}

// Exact values of the quantities one program records, at one PE (its direction d), by the
// names the programs record them under; `computed` gives a quantity's computed value there
// (a cone pairs its roots by the computed sign of β). A missing name: not defined there
// (no exact hit, a negative discriminant).
using ExactValues = std::map<std::string, Real>;
using Computed = std::function<double(const std::string&)>;

void ExactHit(ExactValues& x, const Scene& scene, const Vec3& d) {
  const std::optional<Real> t =
      exact::ObjectHit(scene, 0, scene.camera.from, d, std::max(scene.camera.hither, 0.0));
  if (t) x["t"] = x["t (lowMargin)"] = x["t0 - slack"] = x["t - slack"] = *t;
}

ExactValues SphereExact(const Scene& scene, const Vec3& d,
                        const std::map<std::string, double>& constants) {
  const Primitive& p = scene.objects[0];
  const Sphere& s = std::get<Sphere>(p.shape);
  ExactValues x;
  const RVec dd = R(d);
  const Real r = Real(s.radius);
  RVec f;
  Real tca, disc;
  if (!p.transform) {
    f = R(s.centre) - R(scene.camera.from);
    tca = Dot(f, dd);
    const RVec c = Cross(f, dd);
    disc = r * r - Dot(c, c);
    x["tca"] = tca;
    // The discriminant's bound holds where the clamp of the cross components to r's integer
    // bits did not act (hosts/simd/sphere.cpp; the clamp only moves a miss towards "miss").
    const double range = constants.at("clampRange") - constants.at("crossError");
    if (abs(c.x) < range && abs(c.y) < range && abs(c.z) < range) x["disc"] = disc;
  } else {
    const ExactFrame fr = FrameOf(p, scene.camera.from);
    f = R(s.centre) - fr.eye;
    const RVec dp = fr.Apply(dd);
    x["d'x"] = dp.x, x["d'y"] = dp.y, x["d'z"] = dp.z;
    tca = Dot(f, dp);
    const RVec c = Cross(f, dp);
    const Real n2 = Dot(dp, dp);
    disc = r * r * n2 - Dot(c, c);
    x["tcaN"] = tca;
    x["|d'|²"] = n2;
    const double range = constants.at("clampRange") - constants.at("crossError");
    if (abs(c.x) < range && abs(c.y) < range && abs(c.z) < range) x["disc"] = disc;
  }
  if (disc >= 0) {
    const Real root = Sqrt(disc);
    x["root"] = root;
    x["num0"] = tca - root, x["num1"] = tca + root;
  }
  ExactHit(x, scene, d);
  return x;
}

// A polygon in world space as hosts/simd/polygon.cpp takes it (vertices mapped in double),
// its edge groups (the tracer's canonical edges) and its exact unit normal.
struct ExactPolygon {
  std::vector<Vec3> v;
  std::vector<PolygonEdgeGroup> groups;
  RVec normal;
};
ExactPolygon PolygonOf(const Primitive& p) {
  ExactPolygon w;
  for (const Vec3& x : std::get<Polygon>(p.shape).vertices)
    w.v.push_back(p.transform ? p.transform->ApplyPoint(x) : x);
  Vec3 nn;
  RVec nr{0, 0, 0};
  for (size_t i = 0; i < w.v.size(); ++i) {
    const Vec3 &a = w.v[i], &b = w.v[(i + 1) % w.v.size()];
    nn += Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
    const RVec ra = R(a), rb = R(b);
    nr += RVec{(ra.y - rb.y) * (ra.z + rb.z), (ra.z - rb.z) * (ra.x + rb.x),
               (ra.x - rb.x) * (ra.y + rb.y)};
  }
  w.groups = PolygonEdgeGroups(w.v, Normalize(ScaledDown(nn)));
  w.normal = nr / Norm(nr);
  return w;
}

ExactValues PolygonExact(const Scene& scene, const ExactPolygon& w, const Vec3& d) {
  ExactValues x;
  const RVec eye = R(scene.camera.from), dd = R(d);
  for (size_t gi = 0; gi < w.groups.size(); ++gi)
    for (size_t k = 0; k < w.groups[gi].size(); ++k) {
      const PolygonEdge& e = w.groups[gi][k];
      const RVec c = Cross(R(w.v[e.p]) - eye, R(w.v[e.q]) - eye);
      x[fmt::format("edge {}.{}", gi, k)] = Dot(c, dd) / Norm(c);
    }
  const Real sigma = Dot(w.normal, R(w.v[0]) - eye) >= 0 ? Real(1) : Real(-1);
  x["den"] = sigma * Dot(w.normal, dd);
  ExactHit(x, scene, d);
  return x;
}

// The cone's quadratic in object space (hosts/simd/cone.cpp, docs/simd.md "The program").
template <typename T>
struct ConeQuadratic {
  T da, beta, A, C, disc, wa, sigma;
  Vec3T<T> dPerp, e;
  T q;
};
template <typename T, typename Sq>
ConeQuadratic<T> Quadratic(const Cone& cone, const Vec3T<T>& eye, const Vec3T<T>& dp, Sq sq) {
  const Vec3T<T> base{T(cone.base.x), T(cone.base.y), T(cone.base.z)};
  const Vec3T<T> axis = Vec3T<T>{T(cone.apex.x), T(cone.apex.y), T(cone.apex.z)} - base;
  const T h = sq(Dot(axis, axis));
  const Vec3T<T> a = axis / h;
  ConeQuadratic<T> c;
  c.sigma = (T(cone.apexRadius) - T(cone.baseRadius)) / h;
  const Vec3T<T> w = eye - base;
  c.wa = Dot(w, a);
  const Vec3T<T> wPerp = w - a * c.wa;
  const T rw = T(cone.baseRadius) + c.sigma * c.wa;
  c.da = Dot(dp, a);
  c.dPerp = dp - a * c.da;
  c.e = c.dPerp * rw - wPerp * (c.sigma * c.da);
  c.q = Dot(dp, Cross(w, a));
  c.beta = Dot(wPerp, c.dPerp) - c.sigma * rw * c.da;
  c.A = Dot(c.dPerp, c.dPerp) - c.sigma * c.da * c.sigma * c.da;
  c.C = Dot(wPerp, wPerp) - rw * rw;
  c.disc = Dot(c.e, c.e) - c.q * c.q;
  return c;
}

ExactValues ConeExact(const Scene& scene, const Vec3& d, const Computed& computed) {
  const Primitive& p = scene.objects[0];
  const ExactFrame fr = FrameOf(p, scene.camera.from);
  const ConeQuadratic<Real> c = Quadratic(std::get<Cone>(p.shape), fr.eye, fr.Apply(R(d)), Sqrt);
  ExactValues x;
  x["d'·a"] = c.da, x["σd'·a"] = c.sigma * c.da, x["β"] = c.beta, x["d'·(w×a)"] = c.q;
  x["d'⊥x"] = c.dPerp.x, x["d'⊥y"] = c.dPerp.y, x["d'⊥z"] = c.dPerp.z;
  x["ex"] = c.e.x, x["ey"] = c.e.y, x["ez"] = c.e.z;
  x["A"] = c.A, x["disc"] = c.disc;
  if (c.disc >= 0) {
    x["root"] = Sqrt(c.disc);
    // Q = |β| + √disc with β's computed sign s: its exact counterpart s·β + √disc, and the
    // roots the program pairs with Q/A and C/Q, −s·Q/A and −s·C/Q (hosts/simd/cone.cpp).
    const Real s = computed("β") >= 0 ? Real(1) : Real(-1);
    const Real q = s * c.beta + x["root"];
    x["Q"] = q;
    if (c.A != 0) x["t Q/A"] = -s * q / c.A, x["s Q/A"] = c.wa + x["t Q/A"] * c.da;
    if (q != 0) x["t C/Q"] = -s * c.C / q, x["s C/Q"] = c.wa + x["t C/Q"] * c.da;
  }
  ExactHit(x, scene, d);
  return x;
}

// ---- the directions ------------------------------------------------------------------

// A unit vector at `angle` from the unit `axis`, at azimuth `phi`.
Vec3 AtAngle(const Vec3& axis, double angle, double phi) {
  const Vec3 helper = std::abs(axis.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 u = Normalize(Cross(axis, helper)), v = Cross(axis, u);
  return Normalize(axis * std::cos(angle) +
                   (u * std::cos(phi) + v * std::sin(phi)) * std::sin(angle));
}

// d moved within one ulp of Fd fraction bits so that its two smaller components round by
// almost half an ulp (δ), with random signs; the largest takes up the unit length.
Vec3 Adversarial(const Vec3& d, int dirFracBits, std::mt19937_64& g) {
  int big = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(d[k]) > std::abs(d[big])) big = k;
  double c[3] = {d.x, d.y, d.z};
  double rest = 1;
  for (int k = 0; k < 3; ++k) {
    if (k == big) continue;
    const double q = std::ldexp(std::nearbyint(std::ldexp(c[k], dirFracBits)), -dirFracBits);
    const double side = (g() & 1) ? 1 : -1;
    c[k] = q + side * std::ldexp(0.4999, -dirFracBits);
    rest -= c[k] * c[k];
  }
  c[big] = std::copysign(std::sqrt(std::max(rest, 0.0)), c[big]);
  return {c[0], c[1], c[2]};
}

// Along the arc from `in` to `out` (unit directions with f(in) > target > f(out)), the
// direction where f is `target`, by bisection.
Vec3 Bisect(const Vec3& in, const Vec3& out, double target,
            const std::function<double(const Vec3&)>& f) {
  Vec3 lo = in, hi = out;
  for (int it = 0; it < 80; ++it) {
    const Vec3 mid = Normalize(lo + hi);
    (f(mid) > target ? lo : hi) = mid;
  }
  return lo;
}

// A discriminant target: inside the band (±G·10^-3..±G), just outside it, and at the ladder's
// rungs 4^j·G (j = 0..4) within ±20 % or just above (where a rung's root bound is tightest);
// or, with probability 1/5, none (-inf: a plain ray).
double DiscTarget(double g, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double pick = u(rng);
  if (pick < 0.2) return -kInf;
  if (pick < 0.45) return (u(rng) < 0.5 ? -1 : 1) * g * std::pow(10.0, -3 + 3.3 * u(rng));
  const int j = int(u(rng) * 5);
  return std::ldexp(g, 2 * j) * (pick < 0.7 ? 0.8 + 0.4 * u(rng) : 1 + 0.03 * u(rng));
}

// The world directions for a quadric (sphere, ellipsoid, cone) with discriminant `disc` of a
// world direction: rays toward random points of the object's surface region, and rays on an
// arc from such a point outward bisected to the discriminant's targets.
std::vector<Vec3> QuadricDirections(const Scene& scene,
                                    const std::function<Vec3(std::mt19937_64&)>& surfacePoint,
                                    const std::function<double(const Vec3&)>& disc, double g,
                                    int count, int dirFracBits, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const Vec3 eye = scene.camera.from;
  std::vector<Vec3> dirs;
  while (int(dirs.size()) < count) {
    const Vec3 toward = Normalize(surfacePoint(rng) - eye);
    const double target = DiscTarget(g, rng);
    Vec3 d = toward;
    if (target > -kInf) {
      // Outward: away from the point on a random great circle, until disc < target.
      const double phi = u(rng) * 2 * M_PI;
      Vec3 in = toward, out = toward;
      bool found = false;
      if (disc(in) > target) {
        for (double angle = 1e-6; angle < 1.5 && !found; angle *= 1.6) {
          out = AtAngle(toward, angle, phi);
          found = disc(out) < target;
        }
        if (found) d = Bisect(in, out, target, disc);
      }
      if (!found) continue;
    }
    dirs.push_back(u(rng) < 0.5 ? Adversarial(d, dirFracBits, rng) : d);
  }
  return dirs;
}

// ---- running and comparing -----------------------------------------------------------

// One object program run with an audit over the directions, and the plan it ran with.
struct AuditedRun {
  PrimaryPlan plan;
  Audit audit;
};
AuditedRun RunAudited(const Scene& scene, const SimdOptions& o, const std::vector<Vec3>& dirs) {
  AuditedRun r{PlanPrimaryPass(scene, o), {}};
  bitserial::Machine m(MachineProfileOf(o), int64_t(dirs.size()));
  Directions d;
  for (int k = 0; k < 3; ++k) {
    std::vector<int64_t> raw;
    for (const Vec3& x : dirs) raw.push_back(QuantiseDirection(x[k], r.plan.dirFracBits));
    d.fixed[k] = bitserial::Multi(m, r.plan.direction, std::string("d") + "xyz"[k]);
    d.fixed[k].LoadRaw(raw);
  }
  r.plan.objects[0].program->Run(m, d, &r.audit);
  return r;
}

// The audit's figures of one kind and quantity.
struct Tightness {
  int64_t samples = 0, violations = 0;
  double maxShare = 0;  // the largest |value − exact| / bound (signed for a one-sided claim)
  std::string worst;    // where it was reached
};
using Figures = std::map<std::string, std::map<std::string, Tightness>>;  // kind -> quantity ->

// The largest rung (0..3) of a cone ladder whose threshold x reaches: x >= 4^j·base (j = 0:
// base itself), each threshold rounded as the program rounds it.
int Rung(double x, double base, int frac) {
  int j = 0;
  for (int k = 1; k < 4; ++k)
    if (x >= std::ldexp(std::ceil(std::ldexp(std::ldexp(base, 2 * k), frac)), -frac)) j = k;
  return j;
}

// Compares every claimed value of the run with the exact one; adds to `figures` under `kind`.
void Compare(const std::string& kind, const std::string& what, const Scene& scene,
             const AuditedRun& run, const std::vector<Vec3>& dirs, Figures& figures) {
  std::map<std::string, const Audit::Quantity*> byName;
  for (const Audit::Quantity& q : run.audit.quantities) byName[q.name] = &q;
  std::optional<ExactPolygon> poly;
  if (scene.objects[0].Kind() == ShapeKind::kPolygon) poly = PolygonOf(scene.objects[0]);
  const bool isCone = scene.objects[0].Kind() == ShapeKind::kCone;
  const int F = run.plan.fracBits;
  for (size_t pe = 0; pe < dirs.size(); ++pe) {
    const Computed computed = [&](const std::string& name) {
      return fixed::ToDouble(byName.at(name)->value[pe]);
    };
    const ExactValues x = poly     ? PolygonExact(scene, *poly, dirs[pe])
                          : isCone ? ConeExact(scene, dirs[pe], computed)
                                   : SphereExact(scene, dirs[pe], run.audit.constants);
    for (const Audit::Quantity& q : run.audit.quantities) {
      const double bound = q.bound[pe];
      if (!Audit::Claimed(bound)) continue;
      std::string name = q.name;
      if (isCone && (name == "t Q/A" || name == "t C/Q" || name == "s Q/A" || name == "s C/Q")) {
        // A root's margin by the rung it was taken at: (disc rung, divisor rung).
        const std::string root = name.substr(2);
        const int j = Rung(computed("disc"), run.audit.constants.at("grazeBand"), F);
        const int k = Rung(computed("|D| " + root), run.audit.constants.at("dStar " + root), F);
        name = fmt::format("{} rung {},{}", name, j, k);
      } else if (isCone && (name == "root" || name == "Q")) {
        name = fmt::format("{} rung {}", name,
                           Rung(computed("disc"), run.audit.constants.at("grazeBand"), F));
      }
      if (isCone && q.name == "t (lowMargin)") {
        // A cone's per-PE margin is at most its object-wide tError + u rounded up to the grid
        // (Candidate::lowMargin; rung (0, 0) of the ladders is the divisions' own bound).
        Tightness& m = figures[kind]["lowMargin <= tError + u"];
        const double most = std::ldexp(
            std::ceil(std::ldexp(run.audit.constants.at("tError") * (1 + 1e-12), F)) + 1, -F);
        ++m.samples;
        if (bound > most) ++m.violations;
        if (bound / most > m.maxShare)
          m.maxShare = bound / most,
          m.worst = fmt::format("{}: PE {} margin {:.9g} tError {:.9g}", what, pe, bound, most);
      }
      Tightness& t = figures[kind][name];
      ++t.samples;
      const auto it = x.find(q.name);
      const bool slack = q.side == Audit::Side::kAbove;
      if (it == x.end()) {
        if (slack && (q.name == "t0 - slack" || q.name == "t - slack")) {
          --t.samples;  // no exact hit: nothing to be in front of
          continue;
        }
        if (q.name == "disc" && !isCone) {  // the clamp acted (SphereExact)
          --t.samples;
          continue;
        }
        ++t.violations;  // claimed, but the exact quantity does not exist there (a false hit)
        t.maxShare = kInf, t.worst = fmt::format("{}: PE {} has no exact {}", what, pe, q.name);
        continue;
      }
      const Real diff = FromFixed(q.value[pe]) - it->second;
      const double actual = double(slack ? diff : Real(abs(diff)));
      const double share = actual / bound;
      if (actual > bound) ++t.violations;
      if (share > t.maxShare)
        t.maxShare = share,
        t.worst = fmt::format(
            "{}: PE {} d ({:.17g}, {:.17g}, {:.17g}) value {:.9g} exact {:.9g} bound {:.3g}", what,
            pe, dirs[pe].x, dirs[pe].y, dirs[pe].z, fixed::ToDouble(q.value[pe]),
            double(it->second), bound);
    }
  }
}

// ---- the scenes ----------------------------------------------------------------------

Scene OneObject(const Vec3& eye, const Vec3& at, const Primitive& p, double hither = 0.01) {
  Scene s;
  s.source = "bounds audit";
  s.camera = Camera{eye, at, {0, 1, 0}, 30, hither, 8, 8};
  s.lights = {Light{{5, 5, 5}, {1, 1, 1}}};
  s.materials = {Material{}};
  s.objects = {p};
  return s;
}

Primitive Make(Shape shape, std::optional<Affine> transform = std::nullopt) {
  Primitive p;
  p.shape = std::move(shape);
  p.transform = transform;
  return p;
}

Affine Map(double a00, double a01, double a02, double a10, double a11, double a12, double a20,
           double a21, double a22, const Vec3& shift) {
  Affine t;
  const double m[3][3] = {{a00, a01, a02}, {a10, a11, a12}, {a20, a21, a22}};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.m[r][c] = m[r][c];
    t.m[r][3] = shift[r];
  }
  return t;
}

// The widths every case runs at: fraction bits F and direction fraction bits Fd; the last
// makes the direction's rounding δ the largest error (linear forms close to their bound).
constexpr std::pair<int, int> kWidths[] = {{10, 10}, {16, 16}, {24, 24}, {16, 8}};
constexpr int kRays = 1024;  // directions per case and width

struct Case {
  std::string kind, what;
  Scene scene;
};

std::vector<Case> Cases() {
  std::vector<Case> c;
  const Vec3 o{0, 0, 0};
  // Spheres: typical, tiny, huge and far, far, the eye inside.
  c.push_back(
      {"sphere", "r 1 at 10", OneObject(o, {0, 0, -10}, Make(Sphere{{0.3, -0.2, -10}, 1}))});
  c.push_back(
      {"sphere", "r 0.01 at 5", OneObject(o, {0, 0, -5}, Make(Sphere{{0.01, 0.02, -5}, 0.01}))});
  c.push_back(
      {"sphere", "r 50 at 150", OneObject(o, {0, 0, -150}, Make(Sphere{{20, -10, -150}, 50}))});
  c.push_back({"sphere", "r 2 at 300", OneObject(o, {0, 0, -300}, Make(Sphere{{5, 3, -300}, 2}))});
  c.push_back(
      {"sphere", "eye inside r 20", OneObject(o, {0, 0, -5}, Make(Sphere{{1, 2, -5}, 20}))});
  c.push_back({"sphere", "r 255 at 600 (clamp)",
               OneObject(o, {0, 0, -600}, Make(Sphere{{100, 0, -600}, 255}))});
  c.push_back({"sphere", "hither through it",
               OneObject(o, {0, 0, -3}, Make(Sphere{{0, 0.3, -3}, 2.2}), 1.0)});
  // Ellipsoids: sheared and scaled; squashed to 1/20 and rotated.
  c.push_back({"ellipsoid", "sheared",
               OneObject(o, {0, 0, -12},
                         Make(Sphere{{0, 0, 0}, 1},
                              Map(2, 0.5, 0, 0, 1, 0.3, 0.2, 0, 1.5, {0.5, 0.2, -12})))});
  c.push_back({"ellipsoid", "squashed, rotated",
               OneObject(o, {0, 0, -20},
                         Make(Sphere{{0, 0, 0}, 2},
                              Map(0.8, -0.6, 0, 0.03, 0.04, 0, 0, 0, 1, {0, 0, -20})))});
  // Polygons: a triangle facing the eye; a far quad seen almost edge-on (tiny denominators);
  // a rotated and scaled pentagon; a concave polygon (a fan of triangles).
  c.push_back(
      {"polygon", "triangle at 10",
       OneObject(o, {0, 0, -10},
                 Make(Polygon{{{-1, -1, -10}, {1.2, -0.8, -10.5}, {0.1, 1.3, -9.6}}, {}}))});
  c.push_back({"polygon", "quad edge-on at 200",
               OneObject(o, {0, -2, -200},
                         Make(Polygon{
                             {{-30, -2, -150}, {30, -2, -150}, {30, -2.4, -250}, {-30, -2.4, -250}},
                             {}}))});
  c.push_back({"polygon", "quad, the eye 0.05 above its plane",
               OneObject({0, 0.05, 0}, {0, 0, -20},
                         Make(Polygon{{{-5, 0, -2}, {5, 0, -2}, {5, 0, -40}, {-5, 0, -40}}, {}}))});
  // These two: the eye distance over the farthest vertex (n/D ≈ 1.5e-4) is under twice e_E at
  // F = 16, so the least denominators are barely above their own error (den_min = n/D − e_E);
  // next to a far edge the edge band flags them, next to a far tip some are certain.
  c.push_back({"polygon", "quad, the eye 0.006 above its plane",
               OneObject({0, 0.006, 0}, {0, 0, -20},
                         Make(Polygon{{{-5, 0, -2}, {5, 0, -2}, {5, 0, -40}, {-5, 0, -40}}, {}}))});
  {
    // A plane whose normal has three inexact components (so n̂·d rounds in every product), the
    // eye 0.006 above it, a triangle in it pointing away from the eye.
    const Vec3 n = Normalize(Vec3{0.5, 0.8, 0.33});
    const Vec3 e1 = Normalize(Cross(n, Vec3{0, 0, 1})), e2 = Cross(e1, n);
    const auto at = [&](double x, double z) { return e1 * x + e2 * z - n * 0.006; };
    c.push_back({"polygon", "triangle pointing away, the eye 0.006 above its plane",
                 OneObject(o, e2 * 20.0, Make(Polygon{{at(-3, 2), at(3, 2), at(0.2, 40)}, {}}))});
  }
  c.push_back({"polygon", "pentagon, transformed",
               OneObject(o, {0, 0, -8},
                         Make(Polygon{{{1, 0, 0},
                                       {0.31, 0.95, 0},
                                       {-0.81, 0.59, 0},
                                       {-0.81, -0.59, 0},
                                       {0.31, -0.95, 0}},
                                      {}},
                              Map(1.5, 0.4, 0, 0.2, 1, 0.7, 0, -0.6, 0.8, {0.2, 0.1, -8})))});
  c.push_back(
      {"polygon", "concave at 30",
       OneObject(
           o, {0, 0, -30},
           Make(Polygon{{{-3, -3, -30}, {3, -3, -31}, {0, 0, -30.5}, {3, 3, -30}, {-3, 3, -29}},
                        {}}))});
  // Cones: from the side; along the axis (small divisors, every divisor rung); sheared.
  c.push_back({"cone", "from the side",
               OneObject(o, {0, 0, -10}, Make(Cone{{-2, -1, -10}, 1, {2, 1, -11}, 0.2}))});
  c.push_back({"cone", "along the axis",
               OneObject(o, {0, 0, -10}, Make(Cone{{0, 0, -6}, 0.5, {0.05, 0.02, -14}, 1.2}))});
  c.push_back({"cone", "the eye on the wide side's axis",
               OneObject(o, {0, 0, -8}, Make(Cone{{0, 0, -6}, 2, {0.1, 0, -10}, 0.2}))});
  c.push_back({"cone", "sheared",
               OneObject(o, {0, 0, -9},
                         Make(Cone{{0, -1, 0}, 0.8, {0, 1, 0}, 0.1},
                              Map(1, 0.4, 0, 0, 1, 0, 0.3, 0, 0.7, {0.3, 0, -9})))});
  // Cylinders: from the side; a tube seen end-on (the eye on its axis); squashed and rotated.
  c.push_back({"cylinder", "from the side",
               OneObject(o, {0, 0, -12}, Make(Cone{{-3, 0.5, -12}, 0.6, {3, -0.5, -12.5}, 0.6}))});
  c.push_back({"cylinder", "long, beside the eye",
               OneObject(o, {0, 0, -6}, Make(Cone{{0.9, -0.2, 1}, 0.5, {1.2, 0.3, -12}, 0.5}))});
  c.push_back({"cylinder", "length 80, the eye 0.3 from its side",
               OneObject(o, {0, 0, -40}, Make(Cone{{0.5, 0, 2}, 0.2, {0.6, 0.1, -78}, 0.2}))});
  c.push_back({"cylinder", "the eye inside",
               OneObject(o, {0, 0, -5}, Make(Cone{{0.2, 0, 3}, 1, {-0.3, 0.1, -9}, 1}))});
  c.push_back({"cylinder", "tube end-on",
               OneObject(o, {0, 0, -10}, Make(Cone{{0, 0, -5}, 0.8, {0, 0, -15}, 0.8}))});
  c.push_back({"cylinder", "squashed, rotated",
               OneObject(o, {0, 0, -15},
                         Make(Cone{{0, 0, -2}, 1, {0, 0, 2}, 1},
                              Map(0.2, 0, 0.98, 0, 1, 0, -0.98, 0, 0.2, {0, 0, -15})))});
  return c;
}

// ---- the directions of each kind -----------------------------------------------------

std::vector<Vec3> AuditDirections(const Case& c, const PrimaryPlan& plan, double dStarA,
                                  uint64_t seed) {
  const Primitive& p = c.scene.objects[0];
  const Vec3 eye = c.scene.camera.from;
  const double g = plan.objects[0].bounds.grazeBand;
  const int Fd = plan.dirFracBits;
  std::uniform_real_distribution<double> u(0, 1);
  if (const Sphere* s = std::get_if<Sphere>(&p.shape)) {
    // In object space: points within 1.2 radii of the centre's silhouette; the discriminant
    // of the program (r²|d'|² − |f × d'|², d' = T⁻¹d) in double.
    const Affine inv = p.transform ? p.transform->Inverse() : Affine{};
    const Vec3 eyeObj = inv.ApplyPoint(eye);
    const auto disc = [&](const Vec3& d) {
      const Vec3 dp = inv.ApplyVector(d), f = s->centre - eyeObj, cr = Cross(f, dp);
      return s->radius * s->radius * Dot(dp, dp) - Dot(cr, cr);
    };
    const auto point = [&](std::mt19937_64& rng) {
      const Vec3 dir = AtAngle({0, 0, 1}, std::acos(1 - 2 * u(rng)), 2 * M_PI * u(rng));
      const Vec3 obj = s->centre + dir * (s->radius * (0.2 + u(rng)));
      return p.transform ? p.transform->ApplyPoint(obj) : obj;
    };
    return QuadricDirections(c.scene, point, disc, g, kRays, Fd, seed);
  }
  if (const Cone* cone = std::get_if<Cone>(&p.shape)) {
    const Affine inv = p.transform ? p.transform->Inverse() : Affine{};
    const Vec3 eyeObj = inv.ApplyPoint(eye);
    const auto disc = [&](const Vec3& d) {
      return Quadratic(*cone, eyeObj, inv.ApplyVector(d), [](double x) { return std::sqrt(x); })
          .disc;
    };
    const Vec3 axis = cone->apex - cone->base;
    const auto point = [&](std::mt19937_64& rng) {
      const double s = -0.1 + 1.2 * u(rng);
      const double radius = std::abs(cone->baseRadius + (cone->apexRadius - cone->baseRadius) * s);
      const Vec3 a = Normalize(axis);
      const Vec3 obj =
          cone->base + axis * s + AtAngle(a, M_PI / 2, 2 * M_PI * u(rng)) * (radius * 1.2 * u(rng));
      return p.transform ? p.transform->ApplyPoint(obj) : obj;
    };
    std::vector<Vec3> dirs = QuadricDirections(c.scene, point, disc, g, kRays / 2, Fd, seed);
    // Rays near the axis's direction (small A = |d'⊥|² − (σd'·a)²: the divisor rungs of Q/A):
    // at random angles, and bisected to A = ±4^k·D* just above each rung's threshold.
    std::mt19937_64 rng(seed + 1);
    const Vec3 worldAxis = Normalize(p.transform ? p.transform->ApplyVector(axis) : axis);
    const Vec3 toMid = Normalize(
        (p.transform ? p.transform->ApplyPoint(cone->base + axis * 0.5) : cone->base + axis * 0.5) -
        eye);
    const Vec3 along = Dot(worldAxis, toMid) >= 0 ? worldAxis : worldAxis * -1.0;
    const auto quadA = [&](const Vec3& d) {
      return Quadratic(*cone, eyeObj, inv.ApplyVector(d), [](double x) { return std::sqrt(x); }).A;
    };
    while (int(dirs.size()) < kRays) {
      const double phi = 2 * M_PI * u(rng);
      Vec3 d = AtAngle(along, std::pow(10.0, -4 + 3.7 * u(rng)), phi);
      if (u(rng) < 0.6) {  // |A| just above 4^k·D*, on either side of A = 0
        const double target =
            (u(rng) < 0.3 ? -1 : 1) * std::ldexp(dStarA, 2 * int(u(rng) * 4)) * (1 + 0.03 * u(rng));
        const Vec3 lo = AtAngle(along, 1e-7, phi), hi = AtAngle(along, 1.5, phi);
        if (!(quadA(lo) < target && quadA(hi) > target)) continue;
        d = Bisect(hi, lo, target, quadA);
      }
      dirs.push_back(u(rng) < 0.5 ? Adversarial(d, Fd, rng) : d);
    }
    return dirs;
  }
  // A polygon: toward random points inside, and near its edges and vertices within a few
  // edge bands (the rays whose edge functions are smallest).
  const ExactPolygon w = PolygonOf(p);
  std::mt19937_64 rng(seed);
  std::vector<Vec3> dirs;
  const double band = plan.objects[0].bounds.grazeBand;
  while (int(dirs.size()) < kRays) {
    const size_t n = w.v.size();
    Vec3 d;
    const double pick = u(rng);
    if (pick < 0.3) {
      std::vector<double> wts(n);
      double sum = 0;
      for (double& x : wts) sum += x = -std::log(u(rng) + 1e-300);
      Vec3 pt;
      for (size_t k = 0; k < n; ++k) pt += w.v[k] * (wts[k] / sum);
      d = Normalize(pt - eye);
    } else if (pick < 0.45) {  // toward a vertex from inside (the farthest: the least n̂·d)
      Vec3 centroid;
      for (const Vec3& x : w.v) centroid += x / double(n);
      const Vec3 a = w.v[size_t(u(rng) * n) % n];
      d = Normalize(a + (centroid - a) * std::pow(10.0, -4 + 3.5 * u(rng)) - eye);
    } else {
      const size_t k = size_t(u(rng) * n) % n;
      const Vec3 a = w.v[k], b = w.v[(k + 1) % n];
      const Vec3 pt = pick < 0.85 ? a + (b - a) * u(rng) : a;
      const Vec3 onEdge = Normalize(pt - eye);
      const Vec3 across = Normalize(Cross(onEdge, b - a));
      d = Normalize(onEdge +
                    across * ((u(rng) < 0.5 ? -1 : 1) * band * std::pow(10.0, -1 + 3 * u(rng))));
    }
    dirs.push_back(u(rng) < 0.5 ? Adversarial(d, Fd, rng) : d);
  }
  return dirs;
}

// The bound a quantity's claim is about, as docs/simd.md's table names it.
std::string BoundOf(const std::string& name) {
  static const std::map<std::string, std::string> named = {
      {"tca", "e_tca (tca = f·d)"},
      {"disc", "e_disc (discriminant)"},
      {"t0 - slack", "slack (tLow)"},
      {"t - slack", "slack (tLow)"},
      {"tcaN", "e_tcaN (f·d')"},
      {"|d'|²", "e_dd (d'·d')"},
      {"num0", "e_num (f·d' ∓ root)"},
      {"num1", "e_num (f·d' ∓ root)"},
      {"d'x", "e_d' (d' = T⁻¹d)"},
      {"d'y", "e_d' (d' = T⁻¹d)"},
      {"d'z", "e_d' (d' = T⁻¹d)"},
      {"den", "e_E (denominator σn̂·d)"},
      {"A", "e_A (divisor of Q/A)"},
      {"lowMargin <= tError + u", "lowMargin <= tError + u, rounded up (margin / that)"},
      {"t (lowMargin)", "lowMargin (certain t, per PE)"}};
  if (const auto it = named.find(name); it != named.end()) return it->second;
  if (name == "t") return "e_t (certain t; a cone's tError)";
  if (name.rfind("edge", 0) == 0) return "e_E (edge functions)";
  if (name.rfind("root", 0) == 0) return "e_disc/(2^j·√G) + u (root √disc; cones: 4 rungs)";
  if (name.rfind("Q", 0) == 0) return "e_Q at rung j (divisor of C/Q)";
  if (name.rfind("t Q/A", 0) == 0) return "t margin of Q/A (16 rungs)";
  if (name.rfind("t C/Q", 0) == 0) return "t margin of C/Q (16 rungs)";
  if (name.rfind("s Q/A", 0) == 0 || name.rfind("s C/Q", 0) == 0)
    return "height margin e_s (rungs)";
  return "linear forms c·d (10)";
}

TEST(SimdBoundsAudit, EveryBoundHoldsAgainstTheExactReference) {
  Figures figures;
  uint64_t seed = 1;
  for (const Case& c : Cases())
    for (const auto& [F, Fd] : kWidths) {
      SimdOptions o;
      o.formats.fracBits = F, o.formats.dirFracBits = Fd;
      const PrimaryPlan plan = PlanPrimaryPass(c.scene, o);
      if (plan.objects[0].bounds.alwaysUncertain) continue;  // nothing is claimed
      // A cone's divisor threshold of Q/A (rung 0 of its ladder), from an audited run of one ray.
      const std::map<std::string, double> constants =
          RunAudited(c.scene, o, {Vec3{0, 0, -1}}).audit.constants;
      const double dStarA = constants.count("dStar Q/A") ? constants.at("dStar Q/A") : 0;
      const std::vector<Vec3> dirs = AuditDirections(c, plan, dStarA, seed++);
      const AuditedRun run = RunAudited(c.scene, o, dirs);
      Compare(c.kind, fmt::format("{} {}, F {} Fd {}", c.kind, c.what, F, Fd), c.scene, run, dirs,
              figures);
    }
  // Every quantity (a cone's margins per rung), then the table of docs/simd.md: per kind and
  // bound (the rungs, the three components of d' and the ten linear forms together).
  std::map<std::string, std::map<std::string, Tightness>> table;
  for (const auto& [kind, quantities] : figures)
    for (const auto& [name, t] : quantities) {
      std::printf("  %-9s %-18s samples %6lld  max actual/bound %.3g%s\n", kind.c_str(),
                  name.c_str(), (long long)t.samples, t.maxShare, t.violations ? "  VIOLATED" : "");
      EXPECT_EQ(t.violations, 0) << kind << " " << name << ": " << t.violations << " of "
                                 << t.samples << " samples beyond the bound; worst " << t.worst;
      Tightness& g = table[kind][BoundOf(name)];
      g.samples += t.samples, g.violations += t.violations;
      if (t.maxShare > g.maxShare) g.maxShare = t.maxShare, g.worst = t.worst;
    }
  std::printf(
      "| primitive | bound | samples | max actual/bound | min tightness (bound/actual) |\n");
  for (const auto& [kind, bounds] : table) {
    int64_t samples = 0;
    for (const auto& [bound, t] : bounds) {
      std::printf("| %s | %s | %lld | %.3g | %.3g |\n", kind.c_str(), bound.c_str(),
                  (long long)t.samples, t.maxShare, 1 / t.maxShare);
      RecordProperty(kind + " " + bound,
                     fmt::format("samples {} max actual/bound {:.3g}", t.samples, t.maxShare));
      samples += t.samples;
    }
    std::printf("%s: %lld samples\n", kind.c_str(), (long long)samples);
  }
  // The ladders' rungs (disc rung j, divisor rung k) each root's margin was audited at, over
  // the cones and cylinders: every disc rung, and (a guard on the directions) most divisor
  // rungs of Q/A; C/Q's divisor rungs above 1 need hits far nearer than the cone's far side.
  for (const char* root : {"Q/A", "C/Q"}) {
    int reached = 0;
    std::printf("t %s samples by rung (rows: disc rung j, columns: divisor rung k):\n", root);
    for (int j = 0; j < 4; ++j) {
      std::printf("  j=%d", j);
      for (int k = 0; k < 4; ++k) {
        int64_t n = 0;
        for (const char* kind : {"cone", "cylinder"}) {
          const auto it = figures[kind].find(fmt::format("t {} rung {},{}", root, j, k));
          if (it != figures[kind].end()) n += it->second.samples;
        }
        std::printf(" %6lld", (long long)n);
        reached += n > 0;
      }
      std::printf("\n");
    }
    EXPECT_GE(reached, std::string(root) == "Q/A" ? 14 : 7) << root;
  }
  for (const char* kind : {"cone", "cylinder"})
    for (int j = 0; j < 4; ++j)
      EXPECT_GE(figures[kind][fmt::format("root rung {}", j)].samples, 100)
          << kind << " rung " << j;
}

}  // namespace
}  // namespace zephyr::simd
