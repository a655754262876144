// hosts/trace/intersect.h — ray–primitive intersection in the primitive's own coordinates,
// templated on the scalar (float or double). The tracer applies transforms (docs/background.md, "The ray tracer": the ray
// is mapped by T⁻¹, t is the same in both spaces).
//
// Each routine writes the roots it finds in (tMin, +inf) in increasing order into
// roots[0..1] and returns how many (0, 1 or 2). A miss returns 0.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "hosts/scene/geometry.h"

namespace zephyr {

// The two algebraic forms of the ray–sphere test (docs/background.md, "Precision, accuracy, speed"; Ray Tracing Gems ch. 7).
enum class SphereTest {
  kHearnBaker,  // discriminant r² − |f − (f·d̂)d̂|²: keeps its bits for small, far spheres
  kNaive,       // c = |f|² − r², discriminant b² − c: loses them (kept for the stability study)
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
  return form == SphereTest::kHearnBaker ? IntersectSphereHearnBaker(o, d, centre, radius2, tMin, roots)
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

// Even-odd point-in-polygon test on vertices projected by dropping one axis.
template <typename T>
inline bool InsidePolygon2D(const std::vector<T>& uv, T pu, T pv) {
  bool inside = false;
  const size_t n = uv.size() / 2;
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const T ui = uv[2 * i], vi = uv[2 * i + 1], uj = uv[2 * j], vj = uv[2 * j + 1];
    if ((vi > pv) != (vj > pv) && pu < (uj - ui) * (pv - vi) / (vj - vi) + ui) inside = !inside;
  }
  return inside;
}

}  // namespace zephyr
