// hosts/trace/prepared.h — a primitive as the host tracer tests it (docs/shading.md): the
// scene's object converted once to the tracer's scalar T with what its ray test needs
// precomputed, that test (Intersect), and the unit normal at a hit (NormalAt). The tracer's
// exhaustive loops and the hierarchy's leaves call the same Intersect, so both find the same
// roots bit for bit.
//
//   const Prepared<double> obj = Prepare<double>(scene.objects[i]);
//   double roots[2];  int n = Intersect(obj, SphereTest::kHearnBaker, o, d, tMin, roots);
#pragma once

#include <algorithm>
#include <cmath>
#include <variant>
#include <vector>

#include "hosts/scene/geometry.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/intersect.h"

namespace zephyr {
//
// Each is stored so that the rounding of what its test computes grows with magnitudes the
// secondary-ray offset names (SecondaryOffset, docs/shading.md): a polygon by its plane's
// offset from the world origin, t = (offset − n·o)/(n·d), so a far first vertex costs
// nothing (n·(v0 − o) rounds with |v0 − o|); a transformed polygon is taken to world space
// once (an affine map keeps it planar); a transformed sphere or cone keeps its object space
// with the origin moved to its world anchor (centre, base), o' = A⁻¹(o − anchor), so a
// translation that cancels a far object-space centre rounds nothing away.
template <typename T>
struct Prepared {
  using V = Vec3T<T>;
  ShapeKind kind;
  int material;
  bool transformed = false;  // a sphere or cone with a transform (polygons go to world space)
  T inverse[3][3];           // world -> object, linear part A⁻¹
  V anchor;                  // the world point that is the object-space origin (transformed only)
  // Sphere (transformed: centred on its anchor, so centre = 0)
  V centre;
  T radius = 0, radius2 = 0;
  // Cone (transformed: base = 0)
  V base, axis;
  T height = 0, r0 = 0, slope = 0;
  // Polygon, in world space: the unit Newell normal, the plane n·x = planeOffset, and the
  // sign (±1) that turns the normal into the shading normal (−1 under a mirroring transform,
  // whose world winding is reversed, so that the object's front stays its front).
  V normal;
  T planeOffset = 0;
  int front = 1;
  std::vector<PolygonEdgeGroup> groups;  // the inside, with the shared-edge rule
  std::vector<V> vertices, normals;      // world space; normals only for `pp`
  // The magnitude of the object's own numbers as its test uses them, in world units: part of
  // the bound on the hit point's rounding that sets how far secondary rays leaving it skip
  // (SecondaryOffset). Sphere |c|∞ + r; cone max(|base|∞, |apex|∞) + the larger radius;
  // polygon |plane offset|; a transformed sphere or cone |anchor|∞ + ‖A‖∞ · its size about
  // the anchor (r; |apex − base|∞ + the larger radius).
  T scale = 0;

  V ToObjectPoint(const V& p) const { return ToObjectVector(p - anchor); }
  V ToObjectVector(const V& d) const {
    return {inverse[0][0] * d.x + inverse[0][1] * d.y + inverse[0][2] * d.z,
            inverse[1][0] * d.x + inverse[1][1] * d.y + inverse[1][2] * d.z,
            inverse[2][0] * d.x + inverse[2][1] * d.y + inverse[2][2] * d.z};
  }
  // Normals map by the inverse transpose.
  V NormalToWorld(const V& n) const {
    return {inverse[0][0] * n.x + inverse[1][0] * n.y + inverse[2][0] * n.z,
            inverse[0][1] * n.x + inverse[1][1] * n.y + inverse[2][1] * n.z,
            inverse[0][2] * n.x + inverse[1][2] * n.y + inverse[2][2] * n.z};
  }
};

template <typename T>
Prepared<T> Prepare(const Primitive& p) {
  using V = Vec3T<T>;
  Prepared<T> r;
  r.kind = p.Kind();
  r.material = p.material;
  double scale = 0;
  if (p.Kind() == ShapeKind::kPolygon) {
    const WorldSpacePolygon world = ToWorldSpace(p);
    const std::vector<Vec3>& v = world.vertices;
    const Vec3& n = world.normal;
    r.front = world.front;
    const double offset = Dot(n, v[0]);
    r.normal = V(n);
    r.planeOffset = T(offset);
    r.groups = PolygonEdgeGroups(v, n);
    for (const Vec3& x : v) r.vertices.push_back(V(x));
    for (const Vec3& x : world.normals) r.normals.push_back(V(x));
    scale = std::abs(offset);
  } else if (p.transform) {
    r.transformed = true;
    const Affine inv = p.transform->Inverse();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.inverse[i][j] = T(inv.m[i][j]);
    const double norm = p.transform->LinearNormInf();
    Vec3 anchor;
    if (auto* s = std::get_if<Sphere>(&p.shape)) {
      anchor = s->centre;
      r.radius = T(s->radius);
      r.radius2 = T(s->radius * s->radius);
      scale = norm * s->radius;
    } else {
      const auto& c = std::get<Cone>(p.shape);
      anchor = c.base;
      const Vec3 axis = c.apex - c.base;
      const double h = Length(axis);
      r.axis = V(axis / h);
      r.height = T(h);
      r.r0 = T(c.baseRadius);
      r.slope = T((c.apexRadius - c.baseRadius) / h);
      scale = norm * (MaxAbs(axis) + std::max(c.baseRadius, c.apexRadius));
    }
    const Vec3 world = p.transform->ApplyPoint(anchor);
    r.anchor = V(world);
    scale += MaxAbs(world);
  } else if (auto* s = std::get_if<Sphere>(&p.shape)) {
    r.centre = V(s->centre);
    r.radius = T(s->radius);
    r.radius2 = T(s->radius * s->radius);
    scale = MaxAbs(s->centre) + s->radius;
  } else {
    const auto& c = std::get<Cone>(p.shape);
    const Vec3 axis = c.apex - c.base;
    const double h = Length(axis);
    r.base = V(c.base);
    r.axis = V(axis / h);
    r.height = T(h);
    r.r0 = T(c.baseRadius);
    r.slope = T((c.apexRadius - c.baseRadius) / h);
    scale = std::max(MaxAbs(c.base), MaxAbs(c.apex)) + std::max(c.baseRadius, c.apexRadius);
  }
  r.scale = T(scale);
  return r;
}

// Roots of one prepared object along o + t d (world space), in (tMin, inf).
template <typename T>
int Intersect(const Prepared<T>& obj, SphereTest form, Vec3T<T> o, Vec3T<T> d, T tMin, T* roots) {
  T scale = T(1);
  if (obj.transformed) {
    o = obj.ToObjectPoint(o);
    d = obj.ToObjectVector(d);
  }
  switch (obj.kind) {
    case ShapeKind::kSphere: {
      // The sphere forms want a unit direction; under a transform t_object = t·|d|.
      if (obj.transformed) {
        const T len = Length(d);
        scale = len;
        d = d / len;
      }
      const int n = IntersectSphere(form, o, d, obj.centre, obj.radius2, tMin * scale, roots);
      for (int i = 0; i < n; ++i) roots[i] /= scale;
      return n;
    }
    case ShapeKind::kCone:
      return IntersectCone(o, d, obj.base, obj.axis, obj.height, obj.r0, obj.slope, tMin, roots);
    case ShapeKind::kPolygon: {
      const T nd = Dot(obj.normal, d);
      if (nd == T(0)) return 0;
      const T t = (obj.planeOffset - Dot(obj.normal, o)) / nd;
      if (!(t > tMin)) return 0;
      if (!InsideAlongRay(obj.vertices, obj.groups, o, d, nd > T(0) ? 1 : -1)) return 0;
      roots[0] = t;
      return 1;
    }
  }
  return 0;
}

// Barycentric weights of p in triangle (a, b, c); all >= -eps means inside.
template <typename T>
void Barycentric(const Vec3T<T>& p, const Vec3T<T>& a, const Vec3T<T>& b, const Vec3T<T>& c, T& u,
                 T& v, T& w) {
  const Vec3T<T> v0 = b - a, v1 = c - a, v2 = p - a;
  const T d00 = Dot(v0, v0), d01 = Dot(v0, v1), d11 = Dot(v1, v1), d20 = Dot(v2, v0),
          d21 = Dot(v2, v1);
  const T den = d00 * d11 - d01 * d01;
  v = (d11 * d20 - d01 * d21) / den;
  w = (d00 * d21 - d01 * d20) / den;
  u = T(1) - v - w;
}

// Unit world-space normal at world point p (not yet faced toward the ray).
template <typename T>
Vec3T<T> NormalAt(const Prepared<T>& obj, const Vec3T<T>& worldP) {
  using V = Vec3T<T>;
  const V p = obj.transformed ? obj.ToObjectPoint(worldP) : worldP;
  V n;
  switch (obj.kind) {
    case ShapeKind::kSphere:
      n = (p - obj.centre) / obj.radius;
      break;
    case ShapeKind::kCone: {
      const V w = p - obj.base;
      const T s = Dot(w, obj.axis);
      const V q = w - obj.axis * s;
      const T ql = Length(q);
      const V radial = ql > T(0) ? q / ql : V{};
      n = radial - obj.axis * obj.slope;
      break;
    }
    case ShapeKind::kPolygon:
      n = obj.normal * T(obj.front);
      if (!obj.normals.empty()) {
        // Fan triangles from vertex 0: interpolate in the one that holds p.
        for (size_t i = 1; i + 1 < obj.vertices.size(); ++i) {
          T u, v, w;
          Barycentric(p, obj.vertices[0], obj.vertices[i], obj.vertices[i + 1], u, v, w);
          const T eps = T(-1e-4);
          if (u >= eps && v >= eps && w >= eps) {
            const V m = obj.normals[0] * u + obj.normals[i] * v + obj.normals[i + 1] * w;
            if (Length(m) > T(0)) n = m;
            break;
          }
        }
      }
      break;
  }
  if (obj.transformed) n = obj.NormalToWorld(n);
  return Normalize(n);
}

}  // namespace zephyr
