#include "hosts/trace/tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <utility>

#include "fixed/check.h"
#include "hosts/trace/bvh_walk.h"
#include "hosts/trace/prepared.h"
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
    if (options.accel == Accel::kBvh) {
      hierarchy_.emplace(scene, objects_, options.sphereTest);
      buildWork_.bvhBinned = hierarchy_->Binned();
      buildWork_.bvhNodes = hierarchy_->NodesBuilt();
    }
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
  // covers (BvhWalkT::Answers), else every object. The same object and bits of t either way.
  int Nearest(const V& o, const V& d, T tMin, TraceStats& stats, T& tBest) const {
    if (hierarchy_ && hierarchy_->Answers(o)) return hierarchy_->Nearest(o, d, tMin, stats, tBest);
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
    if (hierarchy_ && hierarchy_->Answers(p))
      return hierarchy_->Transmission(p, toLight, dist, tMin, stats);
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
  std::optional<BvhWalkT<T>> hierarchy_;  // --accel bvh (hosts/trace/bvh_walk.h)
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
