// hosts/trace/exact.h — the exact first-hit reference: every primitive of the scene along a
// ray in 128-bit binary floats (fixed/reference.h RefReal), the one every accuracy figure,
// soundness test and stability study compares against (docs/simd.md, "Accuracy").
//
//   const exact::Hit h = exact::FirstHit(scene, ray, tMin);   // h.object (-1: none), h.t
//
// Inputs are the double values the methods see (the scene's numbers, the double eye ray),
// taken exactly; only the arithmetic after them is 128-bit. Spheres (Hearn–Baker), ellipsoids
// and transformed cones (the ray through the scene's double T⁻¹, then exact), polygons
// (Newell's plane, the tracer's edge functions with the shared-edge rule) and open truncated cones
// as hosts/trace/intersect.h defines them.
#pragma once

#include <optional>
#include <vector>

#include "fixed/reference.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/tracer.h"

namespace zephyr::exact {

using Real = fixed::reference::RefReal;

// A point or direction in 128-bit floats.
struct RealVec {
  Real x, y, z;
  Real operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
};
RealVec Make(const Vec3& v);

// The nearest root of |o + t·d − c|² = r² with t > tMin (d need not be unit); none if the
// ray misses or both roots are <= tMin.
std::optional<Real> SphereHit(const RealVec& centre, const Real& radius, const RealVec& o,
                              const RealVec& d, const Real& tMin);

// A polygon's hit t > tMin, in the polygon's own coordinates (o, d as given).
std::optional<Real> PolygonHit(const Polygon& poly, const RealVec& o, const RealVec& d,
                               const Real& tMin);

// An open truncated cone (NFF `c`): the nearest root t > tMin whose height lies in [0, h]
// on the nappe of non-negative radius.
std::optional<Real> ConeHit(const Cone& cone, const RealVec& o, const RealVec& d, const Real& tMin);

// Object `index` of the scene along origin + t·direction (world space; a transformed object's
// ray goes through T⁻¹ as the scene computes it in double, then exactly).
std::optional<Real> ObjectHit(const Scene& scene, int index, const Vec3& origin,
                              const Vec3& direction, double tMin);

// Untransformed polygons in exactly the same plane (every vertex of one on the other's plane,
// decided in rational arithmetic on the scene's double coordinates): for each object, the
// lowest index of such a polygon (itself when it is the lowest or has none); -1 for every
// other object. Polygons in one plane have equal real t along every ray, so which is first
// is a tie, decided by the lowest index (the SPD teapot's handle and spout are drawn twice,
// with two triangulations of each flat quad).
std::vector<int> CoplanarPolygons(const Scene& scene);

// The first hit along an eye ray: the object (-1: none) and its t (lowest index on a tie,
// and always among polygons in one plane, whose 128-bit t may differ in the last bit).
// `planes` is CoplanarPolygons(scene); without it, it is computed on every call.
struct Hit {
  int object = -1;
  Real t = 0;
};
Hit FirstHit(const Scene& scene, const PrimaryRay& ray, double tMin,
             const std::vector<int>& planes);
Hit FirstHit(const Scene& scene, const PrimaryRay& ray, double tMin);

}  // namespace zephyr::exact
