// hosts/trace/exact.cpp — the exact (128-bit) first-hit reference (hosts/trace/exact.h).
#include "hosts/trace/exact.h"

#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "hosts/trace/intersect.h"

namespace zephyr::exact {

namespace {

RealVec Minus(const RealVec& a, const RealVec& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Real Dot(const RealVec& a, const RealVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The ray mapped by T⁻¹ (the inverse as the scene computes it, in double; then exact).
void ToObject(const Primitive& p, RealVec& o, RealVec& d) {
  if (!p.transform) return;
  const Affine inv = p.transform->Inverse();
  auto row = [&](int r, const RealVec& v, bool point) {
    return Real(inv.m[r][0]) * v.x + Real(inv.m[r][1]) * v.y + Real(inv.m[r][2]) * v.z +
           (point ? Real(inv.m[r][3]) : Real(0));
  };
  o = {row(0, o, true), row(1, o, true), row(2, o, true)};
  d = {row(0, d, false), row(1, d, false), row(2, d, false)};
}

}  // namespace

RealVec Make(const Vec3& v) { return {Real(v.x), Real(v.y), Real(v.z)}; }

// Hearn–Baker: the closest approach v = f − tca·d, disc = (r² − |v|²)/|d|².
std::optional<Real> SphereHit(const RealVec& centre, const Real& radius, const RealVec& o,
                              const RealVec& d, const Real& tMin) {
  const RealVec f = Minus(centre, o);
  const Real dd = Dot(d, d);
  const Real tca = Dot(f, d) / dd;
  const RealVec v = {f.x - tca * d.x, f.y - tca * d.y, f.z - tca * d.z};
  const Real disc = (radius * radius - Dot(v, v)) / dd;
  if (disc < 0) return std::nullopt;
  const Real root = sqrt(disc);
  if (tca - root > tMin) return Real(tca - root);
  if (tca + root > tMin) return Real(tca + root);
  return std::nullopt;
}

// The plane (Newell's normal) and the inside by the tracer's edge functions along the ray,
// with its shared-edge rule (hosts/trace/intersect.h InsideAlongRay).
std::optional<Real> PolygonHit(const Polygon& poly, const RealVec& o, const RealVec& d,
                               const Real& tMin) {
  const size_t n = poly.vertices.size();
  std::vector<RealVec> v;
  for (const Vec3& p : poly.vertices) v.push_back(Make(p));
  RealVec nn{0, 0, 0};
  Vec3 normal;  // the same normal in double, for the tracer's edge groups
  for (size_t i = 0; i < n; ++i) {
    const RealVec &a = v[i], &b = v[(i + 1) % n];
    nn = {nn.x + (a.y - b.y) * (a.z + b.z), nn.y + (a.z - b.z) * (a.x + b.x),
          nn.z + (a.x - b.x) * (a.y + b.y)};
    const Vec3 &p = poly.vertices[i], &q = poly.vertices[(i + 1) % n];
    normal += Vec3{(p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y)};
  }
  const Real nd = Dot(nn, d);
  if (nd == 0) return std::nullopt;
  const Real t = Dot(nn, Minus(v[0], o)) / nd;
  if (!(t > tMin)) return std::nullopt;
  std::vector<Vec3T<Real>> w;
  for (const RealVec& p : v) w.push_back({p.x, p.y, p.z});
  const auto groups = PolygonEdgeGroups(poly.vertices, Normalize(ScaledDown(normal)));
  if (!InsideAlongRay<Real>(w, groups, {o.x, o.y, o.z}, {d.x, d.y, d.z}, nd > 0 ? 1 : -1))
    return std::nullopt;
  return t;
}

// As hosts/trace/intersect.h IntersectCone: A t² + 2β t + C = 0 in the stable form.
std::optional<Real> ConeHit(const Cone& cone, const RealVec& o, const RealVec& d,
                            const Real& tMin) {
  const RealVec base = Make(cone.base), axisFull = Minus(Make(cone.apex), base);
  const Real h = sqrt(Dot(axisFull, axisFull));
  const RealVec a = {axisFull.x / h, axisFull.y / h, axisFull.z / h};
  const Real r0 = Real(cone.baseRadius), slope = (Real(cone.apexRadius) - r0) / h;
  const RealVec w = Minus(o, base);
  const Real da = Dot(d, a), wa = Dot(w, a), rw = r0 + slope * wa;
  const Real qa = Dot(d, d) - da * da - slope * slope * da * da;
  const Real qb = Dot(w, d) - wa * da - slope * rw * da;  // half of b
  const Real qc = Dot(w, w) - wa * wa - rw * rw;
  Real t0, t1;
  if (qa == 0) {
    if (qb == 0) return std::nullopt;
    t0 = t1 = -qc / (2 * qb);
  } else {
    const Real disc = qb * qb - qa * qc;
    if (disc < 0) return std::nullopt;
    const Real root = sqrt(disc);
    const Real q = qb < 0 ? Real(root - qb) : Real(-(qb + root));
    t0 = q / qa;
    t1 = q != 0 ? qc / q : t0;
  }
  if (t1 < t0) std::swap(t0, t1);
  for (const Real& t : {t0, t1}) {
    if (!(t > tMin)) continue;
    const Real s = wa + t * da;
    if (s < 0 || s > h || r0 + slope * s < 0) continue;
    return t;
  }
  return std::nullopt;
}

std::optional<Real> ObjectHit(const Scene& scene, int index, const Vec3& origin,
                              const Vec3& direction, double tMin) {
  const Primitive& p = scene.objects[index];
  if (const Sphere* sp = std::get_if<Sphere>(&p.shape); sp && !p.transform) {
    // A clear miss in double needs no 128-bit test: the ray's closest approach to the
    // centre is farther than the radius by far more than double rounding (~1e-15 of |f|).
    const Vec3 f = sp->centre - origin;
    const double tca = Dot(f, direction) / Dot(direction, direction);
    if (Length(f - direction * tca) > sp->radius + 1e-9 * (Length(f) + sp->radius + 1))
      return std::nullopt;
  }
  RealVec o = Make(origin), d = Make(direction);
  ToObject(p, o, d);
  if (const Sphere* sp = std::get_if<Sphere>(&p.shape))
    return SphereHit(Make(sp->centre), Real(sp->radius), o, d, Real(tMin));
  if (const Polygon* poly = std::get_if<Polygon>(&p.shape))
    return PolygonHit(*poly, o, d, Real(tMin));
  return ConeHit(std::get<Cone>(p.shape), o, d, Real(tMin));
}

namespace {

using Rational = boost::multiprecision::cpp_rational;

// A double as an exact rational.
Rational Exact(double x) {
  using boost::multiprecision::cpp_int;
  int e = 0;
  const double m = std::frexp(x, &e);  // x = m·2^e, |m| in [0.5, 1)
  const cpp_int mant = cpp_int(int64_t(std::ldexp(m, 53)));
  if (e >= 53) return Rational(cpp_int(mant << (e - 53)));
  return Rational(mant, cpp_int(cpp_int(1) << (53 - e)));
}

struct ExactVec {
  Rational x, y, z;
};
ExactVec ExactOf(const Vec3& v) { return {Exact(v.x), Exact(v.y), Exact(v.z)}; }
ExactVec Sub(const ExactVec& a, const ExactVec& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
ExactVec CrossE(const ExactVec& a, const ExactVec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Rational DotE(const ExactVec& a, const ExactVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// A polygon's plane exactly: a vertex and a non-zero normal from three of its vertices (the
// pair of edges from v0 with the largest cross product in double); none if all are collinear.
struct ExactPlane {
  ExactVec point, normal;
  bool valid = false;
};
ExactPlane PlaneOf(const std::vector<Vec3>& v) {
  ExactPlane p;
  size_t bi = 0, bj = 0;
  double best = 0;
  for (size_t i = 1; i < v.size(); ++i)
    for (size_t j = i + 1; j < v.size(); ++j) {
      const double c = Length(Cross(v[i] - v[0], v[j] - v[0]));
      if (c > best) best = c, bi = i, bj = j;
    }
  if (!(best > 0)) return p;
  p.point = ExactOf(v[0]);
  p.normal = CrossE(Sub(ExactOf(v[bi]), p.point), Sub(ExactOf(v[bj]), p.point));
  p.valid = p.normal.x != 0 || p.normal.y != 0 || p.normal.z != 0;
  return p;
}

}  // namespace

std::vector<int> CoplanarPolygons(const Scene& scene) {
  std::vector<int> rep(scene.objects.size(), -1);
  // Bucket by the plane in double (unit normal with its largest component positive, offset),
  // rounded; only polygons in one bucket are compared exactly. A plane split across buckets
  // is only left unmerged (each polygon its own representative).
  std::map<std::array<int64_t, 4>, std::vector<int>> buckets;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Primitive& p = scene.objects[i];
    const Polygon* poly = std::get_if<Polygon>(&p.shape);
    if (!poly || p.transform) continue;
    rep[i] = int(i);
    const std::vector<Vec3>& v = poly->vertices;
    Vec3 nn;
    for (size_t k = 0; k < v.size(); ++k) nn += Cross(v[k], v[(k + 1) % v.size()]);
    const double len = Length(nn);
    if (!(len > 0) || !std::isfinite(len)) continue;
    Vec3 n = nn / len;
    const double big = std::abs(n.x) >= std::abs(n.y) && std::abs(n.x) >= std::abs(n.z) ? n.x
                       : std::abs(n.y) >= std::abs(n.z)                                 ? n.y
                                                                                        : n.z;
    if (big < 0) n = n * -1.0;
    const double off = Dot(n, v[0]);
    auto key = [](double x) { return int64_t(std::llround(x * 1e6)); };
    if (!std::isfinite(off) || std::abs(off) > 1e9) continue;
    buckets[{key(n.x), key(n.y), key(n.z), key(off)}].push_back(int(i));
  }
  for (const auto& [key, members] : buckets) {
    if (members.size() < 2) continue;
    std::vector<std::pair<int, ExactPlane>> planes;  // representatives of this bucket
    for (int i : members) {
      const std::vector<Vec3>& v = std::get<Polygon>(scene.objects[i].shape).vertices;
      for (const auto& [r, plane] : planes) {
        bool on = true;
        for (const Vec3& x : v) on = on && DotE(Sub(ExactOf(x), plane.point), plane.normal) == 0;
        if (on) {
          rep[i] = r;
          break;
        }
      }
      if (rep[i] != i) continue;
      ExactPlane own = PlaneOf(v);
      if (own.valid) planes.push_back({i, std::move(own)});
    }
  }
  return rep;
}

Hit FirstHit(const Scene& scene, const PrimaryRay& ray, double tMin,
             const std::vector<int>& planes) {
  Hit best;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const std::optional<Real> t = ObjectHit(scene, int(i), ray.origin, ray.direction, tMin);
    // A polygon in the best's plane ties with it whatever the last bit of t says.
    if (t && best.object >= 0 && planes[i] >= 0 && planes[i] == planes[best.object]) continue;
    if (t && (best.object < 0 || *t < best.t)) best = {int(i), *t};
  }
  return best;
}

Hit FirstHit(const Scene& scene, const PrimaryRay& ray, double tMin) {
  return FirstHit(scene, ray, tMin, CoplanarPolygons(scene));
}

}  // namespace zephyr::exact
