// hosts/trace/intersect.h — ray–primitive intersection in the primitive's own coordinates,
// templated on the scalar (float or double). The tracer applies transforms (docs/background.md,
// "The ray tracer": the ray is mapped by T⁻¹, t is the same in both spaces).
//
// Each routine writes the roots it finds in (tMin, +inf) in increasing order into
// roots[0..1] and returns how many (0, 1 or 2). A miss returns 0.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "hosts/scene/geometry.h"

namespace zephyr {

// The two algebraic forms of the ray–sphere test (docs/background.md, "Precision, accuracy, speed";
// Ray Tracing Gems ch. 7).
enum class SphereTest {
  kHearnBaker,  // discriminant r² − |f − (f·d̂)d̂|²: keeps its bits for small, far spheres
  kNaive,  // c = |f|² − r², discriminant b² − c: loses them (kept for the stability study)
};

template <typename T>
inline int KeepRoots(T t0, T t1, T tMin, T* roots) {
  if (t0 > t1) std::swap(t0, t1);
  int n = 0;
  if (t0 > tMin) roots[n++] = t0;
  if (t1 > tMin) roots[n++] = t1;
  return n;
}

// d must be unit length. f = o − c.
template <typename T>
inline int IntersectSphereHearnBaker(const Vec3T<T>& o, const Vec3T<T>& d, const Vec3T<T>& centre,
                                     T radius2, T tMin, T* roots) {
  const Vec3T<T> f = o - centre;
  const T b = -Dot(f, d);
  const Vec3T<T> v = f + d * b;  // f minus its projection on d: the closest-approach vector
  const T disc = radius2 - Dot(v, v);
  if (disc < T(0)) return 0;
  const T c = Dot(f, f) - radius2;
  const T q = b + std::copysign(std::sqrt(disc), b);
  if (q == T(0)) return 0;  // grazing the eye itself
  return KeepRoots(c / q, q, tMin, roots);
}

template <typename T>
inline int IntersectSphereNaive(const Vec3T<T>& o, const Vec3T<T>& d, const Vec3T<T>& centre,
                                T radius2, T tMin, T* roots) {
  const Vec3T<T> f = o - centre;
  const T b = -Dot(f, d);
  const T c = Dot(f, f) - radius2;
  const T disc = b * b - c;
  if (disc < T(0)) return 0;
  const T s = std::sqrt(disc);
  return KeepRoots(b - s, b + s, tMin, roots);
}

template <typename T>
inline int IntersectSphere(SphereTest form, const Vec3T<T>& o, const Vec3T<T>& d,
                           const Vec3T<T>& centre, T radius2, T tMin, T* roots) {
  return form == SphereTest::kHearnBaker
             ? IntersectSphereHearnBaker(o, d, centre, radius2, tMin, roots)
             : IntersectSphereNaive(o, d, centre, radius2, tMin, roots);
}

// An open truncated cone: points p with s = (p − base)·axis in [0, height] and distance
// from the axis r0 + slope·s. d need not be unit length.
template <typename T>
inline int IntersectCone(const Vec3T<T>& o, const Vec3T<T>& d, const Vec3T<T>& base,
                         const Vec3T<T>& axis, T height, T r0, T slope, T tMin, T* roots) {
  const Vec3T<T> w = o - base;
  const T da = Dot(d, axis), wa = Dot(w, axis);
  const T rw = r0 + slope * wa;
  const T a = Dot(d, d) - da * da - slope * slope * da * da;
  const T b = T(2) * (Dot(w, d) - wa * da - slope * rw * da);
  const T c = Dot(w, w) - wa * wa - rw * rw;
  T t0, t1;
  if (std::abs(a) < T(1e-12) * Dot(d, d)) {  // ray parallel to a generating line: linear
    if (b == T(0)) return 0;
    t0 = t1 = -c / b;
  } else {
    const T disc = b * b - T(4) * a * c;
    if (disc < T(0)) return 0;
    const T q = T(-0.5) * (b + std::copysign(std::sqrt(disc), b));
    t0 = q / a;
    t1 = (q != T(0)) ? c / q : t0;
  }
  if (t0 > t1) std::swap(t0, t1);
  int n = 0;
  for (T t : {t0, t1}) {
    if (!(t > tMin)) continue;
    const T s = wa + t * da;
    if (s < T(0) || s > height) continue;
    if (r0 + slope * s < T(0)) continue;  // the mirrored nappe of a cone
    if (n == 1 && roots[0] == t) continue;
    roots[n++] = t;
  }
  return n;
}

// A polygon's inside as edge functions along the ray, with an edge rule that gives every
// point of an edge two faces share to exactly one of them (a ray through a roof ridge
// hits the roof). Built once per polygon (PolygonEdgeGroups); tested per ray
// (InsideAlongRay). The SIMD pass's edge functions follow the same rule (hosts/simd).
//
// For a ray o + t d and an edge (p, q), e = d · ((p − o) × (q − o)): its sign says on which
// side of the plane through o, p and q the ray passes. A convex polygon is one group of
// edges; a concave one a fan of triangles from vertex 0 whose parity is the even-odd rule.
// The ray is inside a group when, for every edge, side·s·e > 0, s = sign(d · n) the
// polygon's facing. The edge rule: each edge is stored with its end points in one
// canonical order (the lexicographically smaller vertex first), so two faces sharing it
// compute the same e bit for bit, and e = 0 belongs to the face for which side·s > 0.
struct PolygonEdge {
  int p = 0, q = 0;  // vertex indices, vertex p < vertex q lexicographically (x, then y, z)
  int side = 1;      // +1 or −1: the group's inside is where side · s · e > 0
};
using PolygonEdgeGroup = std::vector<PolygonEdge>;

// The groups of a planar polygon with Newell normal `normal` (convex: one group of every
// edge; concave: the fan triangles (0, i, i+1) that are not collinear).
inline std::vector<PolygonEdgeGroup> PolygonEdgeGroups(const std::vector<Vec3>& v,
                                                       const Vec3& normal) {
  const size_t n = v.size();
  bool convex = true;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 e0 = v[(i + 1) % n] - v[i], e1 = v[(i + 2) % n] - v[(i + 1) % n];
    if (Dot(Cross(e0, e1), normal) < 0) convex = false;
  }
  auto less = [&](int a, int b) {
    return v[a].x != v[b].x ? v[a].x < v[b].x
                            : (v[a].y != v[b].y ? v[a].y < v[b].y : v[a].z < v[b].z);
  };
  auto edge = [&](int a, int b, int tau) {
    return less(a, b) ? PolygonEdge{a, b, tau} : PolygonEdge{b, a, -tau};
  };
  std::vector<PolygonEdgeGroup> groups;
  if (convex) {
    PolygonEdgeGroup g;
    for (size_t i = 0; i < n; ++i) g.push_back(edge(int(i), int((i + 1) % n), 1));
    groups.push_back(g);
  } else {
    for (size_t i = 1; i + 1 < n; ++i) {
      const double tau = Dot(Cross(v[i] - v[0], v[i + 1] - v[0]), normal);
      if (tau == 0) continue;  // a collinear fan triangle covers nothing
      const int s = tau > 0 ? 1 : -1;
      groups.push_back({edge(0, int(i), s), edge(int(i), int(i + 1), s), edge(int(i + 1), 0, s)});
    }
  }
  return groups;
}

// One edge's test: inside when side·s·e > 0, and e = 0 goes to the face with side·s > 0.
template <typename T>
inline bool InsideEdge(T e, int sideTimesFacing) {
  return sideTimesFacing > 0 ? e >= T(0) : e < T(0);
}

// Whether the ray o + t d passes inside the polygon (vertices v, groups from
// PolygonEdgeGroups, facing = sign of d · normal, ±1).
template <typename T>
inline bool InsideAlongRay(const std::vector<Vec3T<T>>& v,
                           const std::vector<PolygonEdgeGroup>& groups, const Vec3T<T>& o,
                           const Vec3T<T>& d, int facing) {
  bool inside = false;
  for (const PolygonEdgeGroup& g : groups) {
    bool in = true;
    for (const PolygonEdge& e : g) {
      const T value = Dot(d, Cross(v[e.p] - o, v[e.q] - o));
      if (!InsideEdge(value, e.side * facing)) {
        in = false;
        break;
      }
    }
    inside ^= in;
  }
  return inside;
}

}  // namespace zephyr
