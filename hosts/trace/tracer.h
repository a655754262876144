// hosts/trace/tracer.h — the Whitted tracer every method shares (paper §2,
// docs/shading.md): exhaustive, as the paper's, or through a bounding-volume hierarchy
// (TraceOptions::accel, --accel bvh; hosts/trace/bvh.h) with the same results bit for bit.
//
// It comes in three pieces so the other methods can swap the middle one:
//   (a) PrimaryRays::At(x, y)        — the eye ray through pixel (x, y), in double;
//   (b) Tracer::FirstHit(ray)        — the first object along it (every object tested, or
//                                      the hierarchy walked);
//   (c) Tracer::ShadeFromPrimaryHit  — the colour from that hit: shadow rays, reflection,
//                                      refraction, recursively (docs/shading.md).
// The sequential method is (a)+(b)+(c); the SIMD method does (b) on the emulated array and
// hands the host a PrimaryHit per pixel for (c). RenderRegion renders any rectangle with no
// per-image state, so a frame rendered alone is bit-identical to the same pixels of a full
// image (the distributed methods rely on it).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fixed/named.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/intersect.h"

namespace zephyr {

enum class Precision { kFloat, kDouble };

// How the host tracer finds what a ray meets (--accel): kNone tests every object (the
// paper's exhaustive method, the default); kBvh walks a bounding-volume hierarchy built
// once per tracer (hosts/trace/bvh.h) and gives the same objects, t and shadow products bit
// for bit (docs/shading.md, "The BVH").
enum class Accel { kNone, kBvh };

// The deepest ray tree a render may ask for (--depth): past any scene's useful bounces
// (POV-Ray's max_trace_level default is 5; each level doubles the rays at worst).
inline constexpr int kMaxDepth = 64;
// Past this depth a render whose scene has a surface that both reflects and transmits warns
// what the tree may cost (2^depth − 1 rays a pixel at worst; POV-Ray's max_trace_level is 5 by
// default, and the SPD README times its scenes at depth 5).
inline constexpr int kDeepTreeWarningDepth = 16;

struct TraceOptions {
  int depth = 5;  // 1 = primary rays only (local light); each bounce adds one level; 1..kMaxDepth
  Precision precision = Precision::kDouble;
  SphereTest sphereTest = SphereTest::kHearnBaker;
  Accel accel = Accel::kNone;
};

// The names of the host tracer's scalar (--precision) and sphere test (--sphere-test;
// "hearn-baker" is another name for hb).
inline constexpr NamedValues<Precision, 2> kPrecisionNames{
    {{{Precision::kFloat, "float"}, {Precision::kDouble, "double"}}}};
inline constexpr NamedValues<SphereTest, 3> kSphereTestNames{
    {{{SphereTest::kHearnBaker, "hb"},
      {SphereTest::kNaive, "naive"},
      {SphereTest::kHearnBaker, "hearn-baker"}}}};
inline constexpr NamedValues<Accel, 2> kAccelNames{
    {{{Accel::kNone, "none"}, {Accel::kBvh, "bvh"}}}};

struct PrimaryRay {
  Vec3 origin;     // the eye
  Vec3 direction;  // unit length
};

// (a) Eye rays. Pixel (0, 0) is the top-left; rows go down. The `angle` spans the centres
// of the top and bottom rows; pixels are square.
class PrimaryRays {
 public:
  explicit PrimaryRays(const Camera& camera);
  PrimaryRay At(int x, int y) const;

 private:
  Vec3 eye_, forward_, right_, up_;
  double pitch_, halfWidth_, halfHeight_;
};

// What the primary pass hands to shading: the object index in Scene::objects (-1: none),
// t = distance from the eye along the unit direction.
struct PrimaryHit {
  int object = -1;
  double t = 0;
  Vec3 direction;
};

enum class RayKind { kPrimary = 0, kShadow = 1, kReflected = 2, kRefracted = 3 };
inline constexpr int kRayKinds = 4;
// Each kind's name in reports, in RayKind order.
inline constexpr const char* kRayKindNames[kRayKinds] = {"primary", "shadow", "reflected",
                                                         "refracted"};

// Counters for one render (or one frame); add them up across frames and workers. They are
// the counted host work a host profile turns into modelled seconds (hosts/testbed/, the
// paper's 1992 testbed); every count is of work done, never of a result's value.
struct TraceStats {
  uint64_t rays[kRayKinds] = {};
  uint64_t tests[kShapeKinds] = {};  // ray–primitive tests performed, by primitive kind
  uint64_t hits = 0;                 // rays (not shadow rays) whose nearest object was found
  uint64_t shades = 0;               // surface points shaded (normal, material, recursion)
  uint64_t lightSamples = 0;         // light sources evaluated at a shaded point (local light)
  uint64_t pixels = 0;               // pixels written
  // --accel bvh (docs/shading.md, "The BVH"); all 0 under --accel none:
  uint64_t nodeVisits = 0;  // hierarchy nodes a ray examined (a leaf's objects or an inner
                            // node's two child boxes)
  uint64_t boxTests = 0;    // ray–box slab tests
  uint64_t bvhBinned = 0;   // the build: primitives binned (Bvh::binnedPrimitives)
  uint64_t bvhNodes = 0;    // the build: nodes made, each with its SAH sweep (Bvh::nodesBuilt)
  void Add(const TraceStats& other);
  // {"rays": {...}, "tests": {...}, "hits", "shades", "lightSamples", "pixels",
  //  "bvh": {"nodeVisits", "boxTests", "binned", "nodesBuilt"}}
  nlohmann::json ToJson() const;
  static TraceStats FromJson(const nlohmann::json& j);  // ToJson's inverse (json exceptions)
};

class Tracer {
 public:
  static std::unique_ptr<Tracer> Create(const Scene& scene, const TraceOptions& options);
  virtual ~Tracer() = default;
  // Not copied: a tracer's hierarchy refers to its own prepared objects (bvh_walk.h).
  Tracer(const Tracer&) = delete;
  Tracer& operator=(const Tracer&) = delete;

  const Scene& GetScene() const { return scene_; }
  const TraceOptions& Options() const { return options_; }
  const PrimaryRays& Rays() const { return rays_; }
  // The work of building this tracer's hierarchy (bvhBinned, bvhNodes; all zero under
  // --accel none): a method adds it once to the host work of whoever built it.
  const TraceStats& BuildWork() const { return buildWork_; }

  // (b) The nearest hit beyond the camera's hither distance, of every object (tested one by
  // one, or found through the hierarchy: the same hit).
  virtual PrimaryHit FirstHit(const PrimaryRay& ray, TraceStats& stats) const = 0;
  // (c) Linear RGB of the pixel whose primary ray from the eye along hit.direction first
  // meets hit.object at hit.t (background when hit.object < 0).
  virtual Vec3 ShadeFromPrimaryHit(const PrimaryHit& hit, TraceStats& stats) const = 0;

  Vec3 TracePixel(int x, int y, TraceStats& stats, PrimaryHit* primary = nullptr) const;

  // For a method that traces the rays elsewhere and shades here (the all-rays-on-the-array
  // method, hosts/wavefront/wavefront.h):
  // The colour the recursion gives a ray from `origin` along the unit `direction` at ray-tree
  // level `level` (1 = a primary ray; it spawns secondary rays below options.depth), hits
  // nearer than tMin (scene units) ignored; counted as one ray of `kind` with its subtree.
  virtual Vec3 TraceRay(const Vec3& origin, const Vec3& direction, double tMin, int level,
                        RayKind kind, TraceStats& stats) const = 0;
  // The light of light `light` let through to p: the product of T over every surface along
  // the segment to it, hits nearer than tMin ignored (docs/shading.md, "Shadows"); counted
  // as one shadow ray.
  virtual double LightThrough(const Vec3& p, int light, double tMin, TraceStats& stats) const = 0;
  // The local term of docs/shading.md at a hit of `object` from what another computed per
  // light i: nl[i] = N·Lᵢ, rv[i] = Rᵢ·(−D) and through[i] = Sᵢ (each of the scene's lights;
  // N faces the ray): the ambient term plus every light with nl > 0 and through > 0. Counted
  // as one shade and one light sample per light.
  virtual Vec3 LocalFromRecord(int object, const double* nl, const double* rv,
                               const double* through, TraceStats& stats) const = 0;

 protected:
  Tracer(const Scene& scene, const TraceOptions& options)
      : scene_(scene), options_(options), rays_(scene.camera) {}
  const Scene& scene_;
  TraceOptions options_;
  PrimaryRays rays_;
  TraceStats buildWork_;
};

// One object against one ray, in double, with the chosen sphere form: the nearest t in
// (tMin, inf), or nullopt. direction need not be unit length (t is in its units). For
// methods that recompute a pixel on the host.
std::optional<double> IntersectObject(const Scene& scene, int object, const Vec3& origin,
                                      const Vec3& direction, double tMin = 0,
                                      SphereTest form = SphereTest::kHearnBaker);

// Snell's law (docs/shading.md, "The colour at a hit"): the unit direction of a ray with unit
// direction d refracted at a surface whose unit normal n faces it (d·n <= 0), with
// eta = n₁/n₂ (the index on d's side over the other's): sinθt = eta·sinθi, in the plane of d
// and n, across the surface. Nothing under total internal reflection (1 − eta²(1 − cos²θi) < 0).
template <typename T>
std::optional<Vec3T<T>> Refract(const Vec3T<T>& d, const Vec3T<T>& n, T eta) {
  const T cosi = -Dot(d, n);
  const T k = T(1) - eta * eta * (T(1) - cosi * cosi);
  if (k < T(0)) return std::nullopt;
  return Normalize(d * eta + n * (eta * cosi - std::sqrt(k)));
}

// Renders the w×h rectangle at (x0, y0): pixels row by row into out (resized to w*h, linear
// RGB), and, if primary is given, the primary hits likewise. onRow is called after each row.
void RenderRegion(const Tracer& tracer, int x0, int y0, int w, int h, std::vector<Vec3>& out,
                  TraceStats& stats, std::vector<PrimaryHit>* primary = nullptr,
                  const std::function<void()>& onRow = {});

// (c) for hits another computed (the SIMD pass's matrix: `hits` row-major, `hitsWidth` ×
// `hitsHeight`): the w×h rectangle at (x0, y0) into out (resized to w*h, linear RGB). Each
// hit's t, off by up to the pass's bound (enough to put the hit point on the wrong side of
// the surface so secondary rays re-hit it; docs/simd.md, "Uncertain pixels"), is refined
// against the one object found, in double (one test, not N), then shaded; every count goes
// to `stats` (one primary ray per pixel). Gives for any rectangle exactly the pixels the
// whole image gives there.
void ShadeFromHits(const Tracer& tracer, const std::vector<PrimaryHit>& hits, int hitsWidth,
                   int hitsHeight, int x0, int y0, int w, int h, std::vector<Vec3>& out,
                   TraceStats& stats);

}  // namespace zephyr
