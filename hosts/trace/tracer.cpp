#include "hosts/trace/tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <utility>

#include "fixed/check.h"
#include "hosts/trace/bvh.h"
#include "hosts/trace/sphere_kernels.h"

namespace zephyr {

PrimaryRays::PrimaryRays(const Camera& c) : eye_(c.from) {
  // Scaled before normalising, so an `up` of 1e300 or 1e-300 neither overflows nor
  // underflows (the reader has rejected a zero or parallel one).
  forward_ = Normalize(ScaledDown(c.at - c.from));
  right_ = Normalize(ScaledDown(Cross(forward_, ScaledDown(c.up))));
  up_ = Cross(right_, forward_);
  const double span = 2 * std::tan(c.angleDegrees * M_PI / 360);
  pitch_ = span / std::max(c.height - 1, 1);
  halfWidth_ = 0.5 * (c.width - 1);
  halfHeight_ = 0.5 * (c.height - 1);
}

PrimaryRay PrimaryRays::At(int x, int y) const {
  const double u = (x - halfWidth_) * pitch_;
  const double v = (halfHeight_ - y) * pitch_;
  return {eye_, Normalize(forward_ + right_ * u + up_ * v)};
}

void TraceStats::Add(const TraceStats& o) {
  for (int i = 0; i < kRayKinds; ++i) rays[i] += o.rays[i];
  for (int i = 0; i < kShapeKinds; ++i) tests[i] += o.tests[i];
  hits += o.hits;
  shades += o.shades;
  lightSamples += o.lightSamples;
  pixels += o.pixels;
  nodeVisits += o.nodeVisits;
  boxTests += o.boxTests;
  bvhBinned += o.bvhBinned;
  bvhNodes += o.bvhNodes;
}

TraceStats TraceStats::FromJson(const nlohmann::json& j) {
  // A count is a whole number from 0 (nlohmann would wrap -5 to 2^64 - 5 and truncate 2.5);
  // a missing key is nlohmann's out_of_range, as before.
  auto count = [](const nlohmann::json& v, const std::string& key) {
    if (!v.is_number_unsigned())
      throw UserError("counted work: " + key + " must be a whole number from 0, got " + v.dump());
    return v.get<uint64_t>();
  };
  TraceStats s;
  for (int i = 0; i < kRayKinds; ++i)
    s.rays[i] = count(j.at("rays").at(kRayKindNames[i]), std::string("rays.") + kRayKindNames[i]);
  for (int i = 0; i < kShapeKinds; ++i)
    s.tests[i] = count(j.at("tests").at(ShapeKindName(ShapeKind(i))),
                       std::string("tests.") + ShapeKindName(ShapeKind(i)));
  s.hits = count(j.at("hits"), "hits");
  s.shades = count(j.at("shades"), "shades");
  s.lightSamples = count(j.at("lightSamples"), "lightSamples");
  s.pixels = count(j.at("pixels"), "pixels");
  const nlohmann::json& bvh = j.at("bvh");
  s.nodeVisits = count(bvh.at("nodeVisits"), "bvh.nodeVisits");
  s.boxTests = count(bvh.at("boxTests"), "bvh.boxTests");
  s.bvhBinned = count(bvh.at("binned"), "bvh.binned");
  s.bvhNodes = count(bvh.at("nodesBuilt"), "bvh.nodesBuilt");
  return s;
}

nlohmann::json TraceStats::ToJson() const {
  nlohmann::json j;
  uint64_t total = 0;
  for (int i = 0; i < kRayKinds; ++i) {
    j["rays"][kRayKindNames[i]] = rays[i];
    total += rays[i];
  }
  j["rays"]["total"] = total;
  total = 0;
  for (int i = 0; i < kShapeKinds; ++i) {
    j["tests"][ShapeKindName(ShapeKind(i))] = tests[i];
    total += tests[i];
  }
  j["tests"]["total"] = total;
  j["hits"] = hits;
  j["shades"] = shades;
  j["lightSamples"] = lightSamples;
  j["pixels"] = pixels;
  j["bvh"] = {{"nodeVisits", nodeVisits},
              {"boxTests", boxTests},
              {"binned", bvhBinned},
              {"nodesBuilt", bvhNodes}};
  return j;
}

Vec3 Tracer::TracePixel(int x, int y, TraceStats& stats, PrimaryHit* primary) const {
  const PrimaryHit hit = FirstHit(rays_.At(x, y), stats);
  if (primary) *primary = hit;
  return ShadeFromPrimaryHit(hit, stats);
}

namespace {

// A primitive converted to the tracer's scalar, with what the tests need precomputed.
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
  if (auto* q = std::get_if<Polygon>(&p.shape)) {
    std::vector<Vec3> v = q->vertices, normals = q->normals;
    if (p.transform) {
      const Affine inv = p.transform->Inverse();
      for (Vec3& x : v) x = p.transform->ApplyPoint(x);
      for (Vec3& n : normals) n = inv.ApplyTransposed(n);
      r.front = p.transform->RelativeDeterminant() < 0 ? -1 : 1;
    }
    Vec3 n;  // Newell's normal, in double
    for (size_t i = 0; i < v.size(); ++i) {
      const Vec3& a = v[i];
      const Vec3& b = v[(i + 1) % v.size()];
      n += Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
    }
    n = Normalize(ScaledDown(n));
    const double offset = Dot(n, v[0]);
    r.normal = V(n);
    r.planeOffset = T(offset);
    r.groups = PolygonEdgeGroups(v, n);
    for (const Vec3& x : v) r.vertices.push_back(V(x));
    for (const Vec3& x : normals) r.normals.push_back(V(x));
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

template <typename T>
class TracerT final : public Tracer {
  using V = Vec3T<T>;

 public:
  TracerT(const Scene& scene, const TraceOptions& options) : Tracer(scene, options) {
    objects_.reserve(scene.objects.size());
    for (const Primitive& p : scene.objects) {
      objects_.push_back(Prepare<T>(p));
      ++kindCount_[int(p.Kind())];
      // Untransformed spheres go to the vector kernel; the rest stay on the scalar path.
      const Prepared<T>& obj = objects_.back();
      const int index = int(objects_.size()) - 1;
      if (obj.kind == ShapeKind::kSphere && !obj.transformed) {
        spheres_.Push(obj.centre, obj.radius2);
        sphereObject_.push_back(index);
      } else {
        scalarObjects_.push_back(index);
      }
    }
    hither_ = T(std::max(scene.camera.hither, 0.0));
    for (size_t i = 0; i < scene.lights.size(); ++i)
      lightColour_.push_back(V(scene.LightColour(i)));
    ambient_ = T(scene.Ambient());
    if (options.accel == Accel::kBvh) BuildHierarchy(scene);
  }

  PrimaryHit FirstHit(const PrimaryRay& ray, TraceStats& stats) const override {
    ++stats.rays[int(RayKind::kPrimary)];
    T t;
    const int object = Nearest(V(ray.origin), V(ray.direction), hither_, stats, t);
    if (object >= 0) ++stats.hits;
    return {object, object >= 0 ? double(t) : 0.0, ray.direction};
  }

  Vec3 ShadeFromPrimaryHit(const PrimaryHit& hit, TraceStats& stats) const override {
    if (hit.object < 0) return scene_.background;
    ZEPHYR_CHECK_LT(size_t(hit.object), objects_.size());
    const V colour = Shade(V(scene_.camera.from), V(hit.direction), hit.object, T(hit.t), 1, stats);
    return Vec3(colour);
  }

 private:
  // The nearest object along o + t d with its first root in (tMin, inf) in tBest: the
  // hierarchy's walk when there is one and the origin lies within the reach its padding
  // covers (BuildHierarchy), else every object. The same object and bits of t either way.
  int Nearest(const V& o, const V& d, T tMin, TraceStats& stats, T& tBest) const {
    if (hierarchy_ && MaxAbs(o) <= originLimit_) return NearestBvh(o, d, tMin, stats, tBest);
    return NearestExhaustive(o, d, tMin, stats, tBest);
  }

  int NearestExhaustive(const V& o, const V& d, T tMin, TraceStats& stats, T& tBest) const {
    for (int k = 0; k < kShapeKinds; ++k) stats.tests[k] += kindCount_[k];
    // The same answer as one scalar pass over objects_ in order keeping strictly nearer
    // roots: the kernel (bit-identical to IntersectSphere) gives the nearest untransformed
    // sphere, lowest index among equal t; the rest join it with ties to the lower index.
    int best = -1;
    const int32_t k = NearestSphere(options_.sphereTest, spheres_, o, d, tMin, &tBest);
    if (k >= 0) best = sphereObject_[k];
    T roots[2];
    for (const int i : scalarObjects_) {
      if (Intersect(objects_[i], options_.sphereTest, o, d, tMin, roots) > 0 &&
          (roots[0] < tBest || (roots[0] == tBest && i < best))) {
        tBest = roots[0];
        best = i;
      }
    }
    return best;
  }

  // ---- The hierarchy (--accel bvh; docs/shading.md, "The BVH") ----------------------------
  // Exactness rests on two things. (1) The objects are tested by the very functions the
  // exhaustive loops call (the leaf's untransformed sphere by IntersectSphere, which the
  // vector kernel matches bit for bit; the rest by Intersect), so a tested object gives the
  // same roots. (2) No object with a root that counts is culled: each box is grown by a pad
  // far above the rounding of both the object's test and the slab test, so any root an
  // object's test returns lies inside the (padded) box's computed slab interval. Both round
  // with the magnitudes of the ray's origin and the scene (|o|, |x| <= reach): the pad is
  // kBvhPadRelative·reach (2⁻²⁴ in double, 2⁻¹² in float: ~10⁸ and ~4000 ulps of reach), a
  // transformed object's box grown further by its map's condition number (its test rounds in
  // object space), and a ray whose origin lies beyond reach (which no hit point or light
  // does) takes the exhaustive loop.
  static constexpr double kBvhPadRelative = std::is_same_v<T, float> ? 0x1p-12 : 0x1p-24;

  struct LeafObject {  // one entry of order[], with an untransformed sphere's data inline
    V centre;
    T radius2 = 0;
    int32_t object = 0;
    bool sphere = false;  // an untransformed sphere: IntersectSphere on centre, radius2
    ShapeKind kind = ShapeKind::kSphere;
    T transparency = 0;  // its material's T, as Transmission multiplies by it
  };

  // What the walk keeps of a node: a leaf's objects leaves_[first, first + count), or an
  // inner node's index in inner_ (count 0). Trivial (no initialisers), so a walk's stack of
  // them costs nothing to declare.
  struct NodeRef {
    int32_t first, count;
  };

  // An inner node as the walk reads it: its two children's boxes by axis then child (one
  // SIMD lane a child) and what each child is. One record per inner node, nothing else
  // between them, aligned to whole cache lines: 112 bytes padded to 128 in double (two
  // 64-byte lines, the pair the L2's adjacent-line prefetch fetches together), 64 in float.
  struct alignas(64) Inner {
    T lo[3][2], hi[3][2];
    NodeRef child[2];
  };

  static T RoundDown(double v) {
    T f = T(v);
    if (double(f) > v) f = std::nextafter(f, -std::numeric_limits<T>::infinity());
    return f;
  }
  static T RoundUp(double v) {
    T f = T(v);
    if (double(f) < v) f = std::nextafter(f, std::numeric_limits<T>::infinity());
    return f;
  }

  void BuildHierarchy(const Scene& scene) {
    if (scene.objects.empty()) return;
    std::vector<Bounds> boxes;
    boxes.reserve(scene.objects.size());
    double reach = MaxAbs(scene.camera.from);
    for (const Light& l : scene.lights) reach = std::max(reach, MaxAbs(l.position));
    for (const Primitive& p : scene.objects) {
      boxes.push_back(WorldBound(p));
      reach = std::max({reach, MaxAbs(boxes.back().lo), MaxAbs(boxes.back().hi)});
    }
    // Hit points lie within the boxes (up to rounding), so twice the reach holds every
    // origin a secondary or shadow ray has.
    originLimit_ = T(2 * reach);
    const double pad = kBvhPadRelative * 2 * reach + double(std::numeric_limits<T>::min());
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const Primitive& p = scene.objects[i];
      if (!p.transform || p.Kind() == ShapeKind::kPolygon) continue;  // polygons: world space
      const double condition =
          p.transform->LinearNormInf() * p.transform->Inverse().LinearNormInf();
      const double grow = kBvhPadRelative * condition * 2 * reach;
      boxes[i].lo = boxes[i].lo - Vec3{grow, grow, grow};
      boxes[i].hi = boxes[i].hi + Vec3{grow, grow, grow};
    }
    const Bvh bvh = BuildBvh(boxes, pad);
    // Each node's box in T, rounded outward.
    std::vector<BvhNodeT<T>> nodes;
    nodes.reserve(bvh.nodes.size());
    for (const BvhNodeT<double>& n : bvh.nodes) {
      BvhNodeT<T> m;
      for (int a = 0; a < 3; ++a) {
        m.lo[a] = RoundDown(n.lo[a]);
        m.hi[a] = RoundUp(n.hi[a]);
      }
      m.first = n.first;
      m.count = n.count;
      nodes.push_back(m);
    }
    // The inner nodes numbered densely in the build's order (a node's near descendants
    // stay near it in memory).
    std::vector<int32_t> innerIndex(nodes.size(), -1);
    int32_t inner = 0;
    for (size_t i = 0; i < nodes.size(); ++i)
      if (nodes[i].count == 0) innerIndex[i] = inner++;
    auto reference = [&](int32_t node) {
      return nodes[node].count > 0 ? NodeRef{nodes[node].first, nodes[node].count}
                                   : NodeRef{innerIndex[node], 0};
    };
    rootBox_ = nodes[0];
    root_ = reference(0);
    // Each inner node's two child boxes side by side, for EntersPair, with what each child
    // is: the walk reads nothing else of a node.
    inner_.resize(size_t(inner));
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i].count > 0) continue;
      Inner& record = inner_[size_t(innerIndex[i])];
      for (int c = 0; c < 2; ++c) {
        const int32_t child = nodes[i].first + c;
        for (int a = 0; a < 3; ++a) {
          record.lo[a][c] = nodes[child].lo[a];
          record.hi[a][c] = nodes[child].hi[a];
        }
        record.child[c] = reference(child);
      }
    }
    for (const int32_t i : bvh.order) {
      const Prepared<T>& obj = objects_[i];
      LeafObject leaf;
      leaf.object = i;
      leaf.kind = obj.kind;
      leaf.sphere = obj.kind == ShapeKind::kSphere && !obj.transformed;
      leaf.centre = obj.centre;
      leaf.radius2 = obj.radius2;
      leaf.transparency = T(scene.materials[obj.material].t);
      leaves_.push_back(leaf);
    }
    hierarchy_ = true;
    buildWork_.bvhBinned = bvh.binnedPrimitives;
    buildWork_.bvhNodes = bvh.nodesBuilt;
  }

#if defined(__SSE2__)
  static constexpr bool kPairSse2 = std::is_same_v<T, double>;
#else
  static constexpr bool kPairSse2 = false;
#endif

  // A ray's set-up for slab tests, made once per ray: its origin and the reciprocals of its
  // direction (±inf for a zero component), and with SSE2 in double each broadcast to both
  // lanes, so a visit loads only the node's boxes.
  struct SlabRay {
    T o[3], inv[3];
#if defined(__SSE2__)
    __m128d vo[3], vinv[3];
#endif
    SlabRay(const V& origin, const V& d)
        : o{origin.x, origin.y, origin.z}, inv{T(1) / d.x, T(1) / d.y, T(1) / d.z} {
#if defined(__SSE2__)
      if constexpr (kPairSse2)
        for (int a = 0; a < 3; ++a) {
          vo[a] = _mm_set1_pd(o[a]);
          vinv[a] = _mm_set1_pd(inv[a]);
        }
#endif
    }
  };

  // Whether the ray's slab interval [tNear, tFar] through box n meets [tMin, tMax]; tNear
  // in *near. A NaN (0·inf: the origin on a box plane along a zero component) constrains
  // nothing on that axis, or culls a ray lying in a padded face, which no object reaches.
  static bool Enters(const BvhNodeT<T>& n, const SlabRay& r, T tMin, T tMax, T* near) {
    T lo = -std::numeric_limits<T>::infinity(), hi = std::numeric_limits<T>::infinity();
    for (int a = 0; a < 3; ++a) {
      const T t0 = (n.lo[a] - r.o[a]) * r.inv[a], t1 = (n.hi[a] - r.o[a]) * r.inv[a];
      const T tn = t0 < t1 ? t0 : t1, tf = t0 < t1 ? t1 : t0;
      if (tn > lo) lo = tn;
      if (tf < hi) hi = tf;
    }
    *near = lo;
    return lo <= hi && hi >= tMin && lo <= tMax;
  }

  // Enters for both children of an inner node at once: bit c of the result set when child c
  // is entered, its tNear in near[c]. With SSE2 (double) two lanes; otherwise the same
  // operations lane by lane (min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b, as
  // minpd and maxpd), so the same boxes are entered on every machine. NaN: as in Enters.
  static inline __attribute__((always_inline)) int EntersPair(const Inner& b, const SlabRay& r,
                                                              T tMin, T tMax, T near[2]) {
#if defined(__SSE2__)
    if constexpr (kPairSse2) {
      // The three axes written out (the compiler keeps the loop at -O2).
      const __m128d a0 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[0]), r.vo[0]), r.vinv[0]);
      const __m128d b0 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[0]), r.vo[0]), r.vinv[0]);
      const __m128d a1 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[1]), r.vo[1]), r.vinv[1]);
      const __m128d b1 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[1]), r.vo[1]), r.vinv[1]);
      const __m128d a2 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[2]), r.vo[2]), r.vinv[2]);
      const __m128d b2 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[2]), r.vo[2]), r.vinv[2]);
      __m128d lo = _mm_set1_pd(-std::numeric_limits<double>::infinity());
      __m128d hi = _mm_set1_pd(std::numeric_limits<double>::infinity());
      lo = _mm_max_pd(_mm_min_pd(a0, b0), lo);
      hi = _mm_min_pd(_mm_max_pd(a0, b0), hi);
      lo = _mm_max_pd(_mm_min_pd(a1, b1), lo);
      hi = _mm_min_pd(_mm_max_pd(a1, b1), hi);
      lo = _mm_max_pd(_mm_min_pd(a2, b2), lo);
      hi = _mm_min_pd(_mm_max_pd(a2, b2), hi);
      _mm_storeu_pd(near, lo);
      const __m128d ok =
          _mm_and_pd(_mm_and_pd(_mm_cmple_pd(lo, hi), _mm_cmpge_pd(hi, _mm_set1_pd(tMin))),
                     _mm_cmple_pd(lo, _mm_set1_pd(tMax)));
      return _mm_movemask_pd(ok);
    }
#endif
    int mask = 0;
    for (int c = 0; c < 2; ++c) {
      T lo = -std::numeric_limits<T>::infinity(), hi = std::numeric_limits<T>::infinity();
      for (int a = 0; a < 3; ++a) {
        const T t0 = (b.lo[a][c] - r.o[a]) * r.inv[a], t1 = (b.hi[a][c] - r.o[a]) * r.inv[a];
        const T tn = t0 < t1 ? t0 : t1, tf = t0 > t1 ? t0 : t1;
        lo = tn > lo ? tn : lo;
        hi = tf < hi ? tf : hi;
      }
      near[c] = lo;
      if (lo <= hi && hi >= tMin && lo <= tMax) mask |= 1 << c;
    }
    return mask;
  }

  // One leaf object's roots along the ray, as the exhaustive loops compute them; counted in
  // tests[kind] (the walk's own counters, added to TraceStats at its end).
  inline __attribute__((always_inline)) int TestLeaf(const LeafObject& leaf, const V& o, const V& d,
                                                     T tMin, T* roots, uint64_t* tests) const {
    ++tests[int(leaf.kind)];
    if (leaf.sphere)  // IntersectSphere's two forms called by name, so both are inlined
      return options_.sphereTest == SphereTest::kHearnBaker
                 ? IntersectSphereHearnBaker(o, d, leaf.centre, leaf.radius2, tMin, roots)
                 : IntersectSphereNaive(o, d, leaf.centre, leaf.radius2, tMin, roots);
    return Intersect(objects_[leaf.object], options_.sphereTest, o, d, tMin, roots);
  }

  // The walk's counts, kept in locals (not behind the TraceStats reference, which the
  // compiler must assume aliases the walk's own state) and added once per ray.
  struct WalkCounts {
    uint64_t boxTests = 0, visits = 0, tests[kShapeKinds] = {};
    void AddTo(TraceStats& stats) const {
      stats.boxTests += boxTests;
      stats.nodeVisits += visits;
      for (int k = 0; k < kShapeKinds; ++k) stats.tests[k] += tests[k];
    }
  };

  struct StackEntry {  // trivial, like NodeRef
    NodeRef node;
    T tNear;
  };

  // Nearest through the hierarchy: nearer child first; a box is skipped only when it is
  // entered strictly beyond the best t (one entered at t may hold a lower index at t). Ties
  // go to the lower index as in NearestExhaustive, whatever the visiting order. The nearer
  // (or only) child entered is visited at once rather than pushed and popped: it was
  // entered at or before the best t, which nothing has changed since, so the pop's test
  // would pass it (the same visits in the same order).
  int NearestBvh(const V& o, const V& d, T tMin, TraceStats& stats, T& tBestOut) const {
    T tBest = std::numeric_limits<T>::infinity();
    int best = -1;
    const SlabRay ray(o, d);
    T near;
    ++stats.boxTests;
    if (!Enters(rootBox_, ray, tMin, tBest, &near)) {
      tBestOut = tBest;
      return best;
    }
    StackEntry stack[kBvhMaxDepth + 2];
    int top = 0;
    NodeRef n = root_;
    T roots[2];
    WalkCounts counts;
    for (;;) {
      ++counts.visits;
      if (n.count > 0) {
        for (int32_t k = n.first; k < n.first + n.count; ++k) {
          const LeafObject& leaf = leaves_[k];
          if (TestLeaf(leaf, o, d, tMin, roots, counts.tests) > 0 &&
              (roots[0] < tBest || (roots[0] == tBest && leaf.object < best))) {
            tBest = roots[0];
            best = leaf.object;
          }
        }
      } else {
        T nearChild[2];
        counts.boxTests += 2;
        const Inner& node = inner_[n.first];
        const int entered = EntersPair(node, ray, tMin, tBest, nearChild);
        // Which child comes next is chosen by branches, not by an index computed from the
        // test: a predicted branch lets the next node's loads start before this node's test
        // has finished (an index would make every visit wait for the last one's test).
        if (entered == 3) {
          if (nearChild[0] <= nearChild[1]) {  // the nearer first
            stack[top++] = {node.child[1], nearChild[1]};
            n = node.child[0];
          } else {
            stack[top++] = {node.child[0], nearChild[0]};
            n = node.child[1];
          }
          continue;
        }
        if (entered == 1) {
          n = node.child[0];
          continue;
        }
        if (entered == 2) {
          n = node.child[1];
          continue;
        }
      }
      // The next entry not entered beyond the best t.
      while (top > 0 && stack[top - 1].tNear > tBest) --top;
      if (top == 0) break;
      n = stack[--top].node;
    }
    counts.AddTo(stats);
    tBestOut = tBest;
    return best;
  }

  // Transmission through the hierarchy: every box the segment (tMin, dist) meets, the
  // crossings (object, roots nearer than dist) collected and multiplied in object order, as
  // TransmissionExhaustive multiplies them (floating-point products depend on the order). An
  // opaque surface crossed makes the product 0 at once (the exhaustive product is 0 too).
  // Child 1 is visited before child 0 (as a stack pushed 0 then 1 would pop them).
  T TransmissionBvh(const V& p, const V& toLight, T dist, T tMin, TraceStats& stats) const {
    struct Crossing {
      int32_t object, count;
      T transparency;
    };
    thread_local std::vector<Crossing> crossed;
    crossed.clear();
    const SlabRay ray(p, toLight);
    T near;
    ++stats.boxTests;
    if (!Enters(rootBox_, ray, tMin, dist, &near)) return T(1);
    NodeRef stack[kBvhMaxDepth + 2];
    int top = 0;
    NodeRef n = root_;
    T roots[2];
    WalkCounts counts;
    for (;;) {
      ++counts.visits;
      if (n.count > 0) {
        for (int32_t k = n.first; k < n.first + n.count; ++k) {
          const LeafObject& leaf = leaves_[k];
          const int found = TestLeaf(leaf, p, toLight, tMin, roots, counts.tests);
          int count = 0;
          for (int i = 0; i < found; ++i) {
            if (roots[i] >= dist) break;
            ++count;
          }
          if (count == 0) continue;
          if (leaf.transparency == T(0)) {
            counts.AddTo(stats);
            return T(0);
          }
          crossed.push_back({leaf.object, count, leaf.transparency});
        }
      } else {
        counts.boxTests += 2;
        T nearChild[2];
        const Inner& node = inner_[n.first];
        const int entered = EntersPair(node, ray, tMin, dist, nearChild);
        if (entered == 3) {  // (branches, not an index: as in NearestBvh)
          stack[top++] = node.child[0];
          n = node.child[1];
          continue;
        }
        if (entered == 1) {
          n = node.child[0];
          continue;
        }
        if (entered == 2) {
          n = node.child[1];
          continue;
        }
      }
      if (top == 0) break;
      n = stack[--top];
    }
    counts.AddTo(stats);
    std::sort(crossed.begin(), crossed.end(),
              [](const Crossing& a, const Crossing& b) { return a.object < b.object; });
    T through = T(1);
    for (const Crossing& c : crossed)
      for (int i = 0; i < c.count; ++i) {
        through *= c.transparency;
        if (through == T(0)) return through;
      }
    return through;
  }

  // How far a secondary or shadow ray leaving a hit skips, so it does not re-hit the
  // surface it leaves: a bound on the hit point's error, which grows with the magnitudes
  // that computed it — the ray's origin, the distance t and the object's own numbers as its
  // test uses them (Prepared::scale) — times 1e-9 (double) or 1e-4 (float, ~7 digits). Tied
  // to the hit, not to the scene: a far "infinite" floor changes nothing here
  // (docs/shading.md).
  T SecondaryOffset(const V& o, T t, const Prepared<T>& obj) const {
    const T relative = std::is_same_v<T, float> ? T(1e-4) : T(1e-9);
    return relative * (MaxAbs(o) + std::abs(t) + obj.scale);
  }

  // Light let through toward a light `dist` away: every surface crossed multiplies it by
  // that surface's transparency T (0 for opaque: full shadow). Hits nearer than tMin (the
  // offset of the hit the ray leaves) are ignored.
  T Transmission(const V& p, const V& toLight, T dist, T tMin, TraceStats& stats) const {
    ++stats.rays[int(RayKind::kShadow)];
    if (hierarchy_ && MaxAbs(p) <= originLimit_)
      return TransmissionBvh(p, toLight, dist, tMin, stats);
    return TransmissionExhaustive(p, toLight, dist, tMin, stats);
  }

  T TransmissionExhaustive(const V& p, const V& toLight, T dist, T tMin, TraceStats& stats) const {
    for (int k = 0; k < kShapeKinds; ++k) stats.tests[k] += kindCount_[k];
    T through = T(1);
    T roots[2];
    for (const Prepared<T>& obj : objects_) {
      const int n = Intersect(obj, options_.sphereTest, p, toLight, tMin, roots);
      for (int i = 0; i < n; ++i) {
        if (roots[i] >= dist) break;
        through *= T(scene_.materials[obj.material].t);
        if (through == T(0)) return through;
      }
    }
    return through;
  }

  V Trace(const V& o, const V& d, T tMin, int depth, RayKind kind, TraceStats& stats) const {
    ++stats.rays[int(kind)];
    T t;
    const int object = Nearest(o, d, tMin, stats, t);
    if (object < 0) return V(scene_.background);
    ++stats.hits;
    return Shade(o, d, object, t, depth, stats);
  }

  V Shade(const V& o, const V& d, int object, T t, int depth, TraceStats& stats) const {
    ++stats.shades;
    const Prepared<T>& obj = objects_[object];
    const Material& m = scene_.materials[obj.material];
    const V p = o + d * t;
    V n = NormalAt(obj, p);
    const bool inside = Dot(n, d) > T(0);
    if (inside) n = -n;  // face the viewer
    const V surface(m.colour);
    const T leave = SecondaryOffset(o, t, obj);
    // The ambient term (SPD's, for scenes with lights of no colour): unshadowed.
    V colour = surface * (T(m.kd) * ambient_);
    for (size_t i = 0; i < scene_.lights.size(); ++i) {
      ++stats.lightSamples;
      V toLight = V(scene_.lights[i].position) - p;
      const T dist = Length(toLight);
      toLight = toLight / dist;
      const T nl = Dot(n, toLight);
      if (nl <= T(0)) continue;
      const T through = Transmission(p, toLight, dist, leave, stats);
      if (through == T(0)) continue;
      // Phong: the mirror direction of the light against the direction to the eye.
      const V r = n * (T(2) * nl) - toLight;
      colour += LightTerm(m, surface, i, nl, -Dot(r, d)) * through;
    }
    if (depth < options_.depth) {
      const T dn = Dot(d, n);  // < 0: n faces the incoming ray
      const V reflected = d - n * (T(2) * dn);
      if (m.ks > 0)
        colour += Trace(p, reflected, leave, depth + 1, RayKind::kReflected, stats) * T(m.ks);
      if (m.t > 0) {
        // Snell: entering uses 1/ior, leaving uses ior/1. Under total internal reflection
        // the transmitted share is reflected.
        const T eta = inside ? T(m.ior) : T(1) / T(m.ior);
        const std::optional<V> refracted = Refract(d, n, eta);
        colour += Trace(p, refracted ? *refracted : reflected, leave, depth + 1,
                        refracted ? RayKind::kRefracted : RayKind::kReflected, stats) *
                  T(m.t);
      }
    }
    return colour;
  }

  // One light's unshadowed local term at a surface of material m and colour `surface` with
  // nl = N·L > 0 and rv = R·(−D) (docs/shading.md, "The colour at a hit").
  V LightTerm(const Material& m, const V& surface, size_t light, T nl, T rv) const {
    const V& lightColour = lightColour_[light];
    V local = Mul(surface, lightColour) * (T(m.kd) * nl);
    if (m.ks > 0 && rv > T(0)) local += lightColour * (T(m.ks) * std::pow(rv, T(m.shine)));
    return local;
  }

 public:
  Vec3 TraceRay(const Vec3& origin, const Vec3& direction, double tMin, int level, RayKind kind,
                TraceStats& stats) const override {
    return Vec3(Trace(V(origin), V(direction), T(tMin), level, kind, stats));
  }

  double LightThrough(const Vec3& p, int light, double tMin, TraceStats& stats) const override {
    ZEPHYR_CHECK(light >= 0 && size_t(light) < scene_.lights.size());
    V toLight = V(scene_.lights[light].position) - V(p);
    const T dist = Length(toLight);
    return double(Transmission(V(p), toLight / dist, dist, T(tMin), stats));
  }

  Vec3 LocalFromRecord(int object, const double* nl, const double* rv, const double* through,
                       TraceStats& stats) const override {
    ZEPHYR_CHECK(object >= 0 && size_t(object) < objects_.size());
    ++stats.shades;
    const Material& m = scene_.materials[objects_[object].material];
    const V surface(m.colour);
    V colour = surface * (T(m.kd) * ambient_);
    for (size_t i = 0; i < scene_.lights.size(); ++i) {
      ++stats.lightSamples;
      if (nl[i] <= 0 || through[i] <= 0) continue;
      colour += LightTerm(m, surface, i, T(nl[i]), T(rv[i])) * T(through[i]);
    }
    return Vec3(colour);
  }

 private:
  std::vector<Prepared<T>> objects_;
  SphereArrays<T> spheres_;         // the untransformed spheres, for NearestSphere
  std::vector<int> sphereObject_;   // spheres_ index -> objects_ index (increasing)
  std::vector<int> scalarObjects_;  // every other object, in order
  uint64_t kindCount_[kShapeKinds] = {};
  std::vector<V> lightColour_;  // Scene::LightColour of each light
  T ambient_, hither_;
  // --accel bvh: the hierarchy (empty: none), its objects in leaf order, and the largest
  // |coordinate| of an origin it answers for (BuildHierarchy).
  bool hierarchy_ = false;
  BvhNodeT<T> rootBox_;
  NodeRef root_{0, 0};
  std::vector<Inner> inner_;  // the inner nodes' records (Inner)
  std::vector<LeafObject> leaves_;
  T originLimit_ = 0;
};

}  // namespace

std::unique_ptr<Tracer> Tracer::Create(const Scene& scene, const TraceOptions& options) {
  if (options.depth < 1 || options.depth > kMaxDepth)
    throw UserError("the ray-tree depth must be 1.." + std::to_string(kMaxDepth) + ", got " +
                    std::to_string(options.depth));
  // The reader has held the scene to double's limit; float's is lower (docs/scene-format.md).
  const bool isFloat = options.precision == Precision::kFloat;
  const double limit = isFloat ? kMagnitudeLimitFloat : kMagnitudeLimitDouble;
  if (const auto fault = FindMagnitudeOver(scene, limit)) {
    char what[320];
    std::snprintf(what, sizeof what, ": %s reaches %.3g, beyond %.0e, where squares overflow %s%s",
                  fault->what.c_str(), fault->magnitude, limit, isFloat ? "float" : "double",
                  isFloat ? " (use --precision double)" : " (scale the scene down)");
    throw UserError(fault->where.ToString() + what);
  }
  if (options.precision == Precision::kFloat)
    return std::make_unique<TracerT<float>>(scene, options);
  return std::make_unique<TracerT<double>>(scene, options);
}

std::optional<double> IntersectObject(const Scene& scene, int object, const Vec3& origin,
                                      const Vec3& direction, double tMin, SphereTest form) {
  ZEPHYR_CHECK(object >= 0 && size_t(object) < scene.objects.size());
  const Prepared<double> obj = Prepare<double>(scene.objects[object]);
  double roots[2];
  if (Intersect(obj, form, origin, direction, tMin, roots) == 0) return std::nullopt;
  return roots[0];
}

void RenderRegion(const Tracer& tracer, int x0, int y0, int w, int h, std::vector<Vec3>& out,
                  TraceStats& stats, std::vector<PrimaryHit>* primary,
                  const std::function<void()>& onRow) {
  const Camera& c = tracer.GetScene().camera;
  ZEPHYR_CHECK(x0 >= 0 && y0 >= 0 && w >= 0 && h >= 0 && x0 + w <= c.width && y0 + h <= c.height);
  out.resize(size_t(w) * h);
  if (primary) primary->resize(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      out[i] = tracer.TracePixel(x0 + x, y0 + y, stats, primary ? &(*primary)[i] : nullptr);
      ++stats.pixels;
    }
    if (onRow) onRow();
  }
}

void ShadeFromHits(const Tracer& tracer, const std::vector<PrimaryHit>& hits, int hitsWidth,
                   int hitsHeight, int x0, int y0, int w, int h, std::vector<Vec3>& out,
                   TraceStats& stats) {
  ZEPHYR_CHECK(x0 >= 0 && y0 >= 0 && w >= 0 && h >= 0 && x0 + w <= hitsWidth &&
               y0 + h <= hitsHeight);
  ZEPHYR_CHECK_EQ(hits.size(), size_t(hitsWidth) * hitsHeight);
  out.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      PrimaryHit hit = hits[size_t(y0 + y) * hitsWidth + x0 + x];
      ++stats.rays[int(RayKind::kPrimary)];
      // Refine t against the one object found (ShadeFromHits' comment).
      if (hit.object >= 0) {
        const Scene& scene = tracer.GetScene();
        const double tMin = std::max(scene.camera.hither, 0.0);
        ++stats.tests[int(scene.objects[hit.object].Kind())];
        ++stats.hits;
        if (auto t = IntersectObject(scene, hit.object, scene.camera.from, hit.direction, tMin,
                                     tracer.Options().sphereTest))
          hit.t = *t;
      }
      out[size_t(y) * w + x] = tracer.ShadeFromPrimaryHit(hit, stats);
      ++stats.pixels;
    }
}

}  // namespace zephyr
