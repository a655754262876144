// LIBS: -lembree3
// tools/bench/trace.cpp — ray–sphere tests per second on one core: the plain scalar loop
// (NearestSphereScalar), the engine's Highway kernel (hosts/trace/sphere_kernels.h: many spheres
// per vector, Hearn–Baker form, float and double, bit-identical to the scalar loop), and
// Embree 3's BVH with its built-in sphere primitive tracing the same primary rays, for 10,
// 100 and 1000 spheres. Then the host tracer's own hierarchy (--accel bvh, hosts/trace/bvh.h)
// against Embree in rays/s on one core, on the same jittered-grid sphere scenes of 1 000 and
// 100 000 spheres; on seq's scene (4096 random spheres, 384×384) its primary rays, incoherent
// rays (random directions from points on the spheres, as reflected and refracted rays leave
// them) and shadow rays (Embree's any-hit rtcOccluded1 against our transmission product);
// seq's render with --accel bvh against --accel none in wall time; and what seq's rays alone
// would take at Embree's rates, the best ratio a single-ray tracer could give here
// (docs/shading.md, "Speed"). Prints medians of repeats and the ratios.
#include <embree3/rtcore.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "hosts/scene/gen.h"
#include "hosts/trace/bvh.h"
#include "hosts/trace/sphere_kernels.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace {

template <typename T>
SphereArrays<T> Pack(const Scene& s) {
  SphereArrays<T> a;
  for (const Primitive& p : s.objects) {
    const auto& sp = std::get<Sphere>(p.shape);
    a.Push(Vec3T<T>(sp.centre), T(sp.radius * sp.radius));
  }
  return a;
}

template <typename F>
double MedianSeconds(int repeats, F&& f) {
  std::vector<double> s;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(s.begin(), s.end());
  return s[s.size() / 2];
}

struct Hit {
  int32_t object;
  uint64_t tBits;
  bool operator==(const Hit&) const = default;
};

template <typename T>
uint64_t Bits(T v) {
  if constexpr (sizeof(T) == 4)
    return std::bit_cast<uint32_t>(v);
  else
    return std::bit_cast<uint64_t>(v);
}

// Scalar loop and engine kernel on the same rays: seconds each, and whether every hit
// (object and bits of t) agrees.
template <typename T>
void TimeScalarAndKernel(const Scene& scene, const std::vector<PrimaryRay>& rays, int repeats,
                         double& scalar, double& kernel, bool& exact, std::vector<int32_t>* hits) {
  const SphereArrays<T> spheres = Pack<T>(scene);
  std::vector<Vec3T<T>> o, d;
  for (const PrimaryRay& r : rays) {
    o.push_back(Vec3T<T>(r.origin));
    d.push_back(Vec3T<T>(r.direction));
  }
  std::vector<Hit> a(rays.size()), b(rays.size());
  const SphereTest form = SphereTest::kHearnBaker;
  scalar = MedianSeconds(repeats, [&] {
    for (size_t i = 0; i < rays.size(); ++i) {
      T t;
      a[i].object = NearestSphereScalar(form, spheres, o[i], d[i], T(0), &t);
      a[i].tBits = Bits(t);
    }
  });
  kernel = MedianSeconds(repeats, [&] {
    for (size_t i = 0; i < rays.size(); ++i) {
      T t;
      b[i].object = NearestSphere(form, spheres, o[i], d[i], T(0), &t);
      b[i].tBits = Bits(t);
    }
  });
  exact = a == b;
  if (hits) {
    hits->clear();
    for (const Hit& h : a) hits->push_back(h.object);
  }
}

// Every primary ray of the scene's view, row by row.
std::vector<PrimaryRay> ViewRays(const Scene& scene) {
  const PrimaryRays camera(scene.camera);
  std::vector<PrimaryRay> rays;
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x) rays.push_back(camera.At(x, y));
  return rays;
}

// Embree 3's scene of `scene`'s spheres (built-in sphere primitive, float; one thread),
// committed: the commit's (the build's) seconds in *build when given.
struct EmbreeSpheres {
  RTCDevice device = rtcNewDevice("threads=1");
  RTCScene scene = rtcNewScene(device);
  explicit EmbreeSpheres(const Scene& s, double* build = nullptr) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), s.objects.size()));
    for (size_t i = 0; i < s.objects.size(); ++i) {
      const auto& sp = std::get<Sphere>(s.objects[i].shape);
      v[4 * i] = float(sp.centre.x);
      v[4 * i + 1] = float(sp.centre.y);
      v[4 * i + 2] = float(sp.centre.z);
      v[4 * i + 3] = float(sp.radius);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    const double seconds = MedianSeconds(1, [&] { rtcCommitScene(scene); });
    if (build) *build = seconds;
  }
  ~EmbreeSpheres() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
};

// Embree 3 (one thread) with its built-in sphere primitive: the nearest sphere of each ray
// (-1: none) beyond `tnear`, the build's seconds in *build and the median seconds of
// `repeats` passes over the rays in *seconds.
std::vector<int32_t> EmbreeFirstHits(const Scene& scene, const std::vector<PrimaryRay>& rays,
                                     int repeats, double* build, double* seconds, float tnear = 0) {
  const EmbreeSpheres es(scene, build);
  std::vector<int32_t> hits(rays.size());
  *seconds = MedianSeconds(repeats, [&] {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = 0; i < rays.size(); ++i) {
      RTCRayHit rh{};
      const PrimaryRay& r = rays[i];
      rh.ray.org_x = float(r.origin.x);
      rh.ray.org_y = float(r.origin.y);
      rh.ray.org_z = float(r.origin.z);
      rh.ray.dir_x = float(r.direction.x);
      rh.ray.dir_y = float(r.direction.y);
      rh.ray.dir_z = float(r.direction.z);
      rh.ray.tnear = tnear;
      rh.ray.tfar = std::numeric_limits<float>::infinity();
      rh.ray.mask = ~0u;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(es.scene, &context, &rh);
      hits[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : int32_t(rh.hit.primID);
    }
  });
  return hits;
}

void Run(int count, int size) {
  const Scene scene = GenerateRandomSpheres({count, 1, size, size});
  const std::vector<PrimaryRay> rays = ViewRays(scene);
  const size_t nRays = rays.size();
  const double tests = double(nRays) * count;
  const int repeats = 5;

  double scalarF, kernelF, scalarD, kernelD;
  bool exactF, exactD;
  std::vector<int32_t> scalarHit;
  TimeScalarAndKernel<float>(scene, rays, repeats, scalarF, kernelF, exactF, &scalarHit);
  TimeScalarAndKernel<double>(scene, rays, repeats, scalarD, kernelD, exactD, nullptr);

  double build, embree;
  const std::vector<int32_t> embreeHit = EmbreeFirstHits(scene, rays, repeats, &build, &embree);

  size_t embreeAgree = 0;
  for (size_t i = 0; i < nRays; ++i) embreeAgree += embreeHit[i] == scalarHit[i];
  std::printf(
      "%5d spheres %4dx%-4d | float: scalar %6.3f Gt/s, kernel %6.3f Gt/s x%.1f%s | "
      "double: scalar %6.3f Gt/s, kernel %6.3f Gt/s x%.1f%s | embree %7.3f ms "
      "(+build %.3f ms) = %6.3f Gt/s-equiv, agrees %.4f\n",
      count, size, size, tests / scalarF * 1e-9, tests / kernelF * 1e-9, scalarF / kernelF,
      exactF ? " exact" : " MISMATCH", tests / scalarD * 1e-9, tests / kernelD * 1e-9,
      scalarD / kernelD, exactD ? " exact" : " MISMATCH", embree * 1e3, build * 1e3,
      tests / embree * 1e-9, double(embreeAgree) / nRays);
}

// `count` spheres in the generator's region (4.4 × 4.4 × 6 in front of the eye,
// GenerateRandomSpheres' camera, lights and materials), one per cell of a jittered grid so none
// overlap and the placement is O(count) (the generator's own rejection test is O(count²): minutes
// at 10⁵).
Scene GridSpheres(int count, int size) {
  Scene s = GenerateRandomSpheres({1, 1, size, size});
  s.objects.clear();
  const int side = int(std::ceil(std::cbrt(double(count))));
  const double cell[3] = {4.4 / side, 4.4 / side, 6.0 / side};
  const double radius = 0.5 * std::min({cell[0], cell[1], cell[2]});
  uint64_t state = 12345;
  auto uniform = [&] {  // SplitMix64 in [0, 1)
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  };
  for (int i = 0; i < count; ++i) {
    const int c[3] = {i % side, (i / side) % side, i / (side * side)};
    const double r = radius * (0.6 + 0.4 * uniform());
    Vec3 centre;
    double lo[3] = {-2.2, -2.2, -4};
    double p[3];
    for (int a = 0; a < 3; ++a)
      p[a] = lo[a] + cell[a] * (c[a] + 0.5) + (cell[a] / 2 - r) * (2 * uniform() - 1);
    centre = {p[0], p[1], p[2]};
    Primitive prim;
    prim.shape = Sphere{centre, r};
    prim.material = int(i % s.materials.size());
    s.objects.push_back(prim);
  }
  return s;
}

// Rays per second of one kind, ours (--accel bvh, double, the hierarchy built before the
// clock) and Embree's (float, one thread), on one scene: medians of 5.
struct RayRates {
  double ours = 0, embree = 0;  // rays/s
  double visits = 0;            // our node visits a ray
  double agree = 0;             // fraction of rays with the same answer (object; occluded)
  double embreeBuild = 0;       // seconds of Embree's build (NearestRates)
};

// Nearest hits of `rays` beyond tMin: ours (FirstHit, whose tMin is the scene's hither) and
// Embree's rtcIntersect1.
RayRates NearestRates(const Scene& scene, const Tracer& tracer,
                      const std::vector<PrimaryRay>& rays) {
  RayRates r;
  std::vector<int32_t> ours(rays.size());
  TraceStats stats;
  const double n = double(rays.size());
  r.ours = n / MedianSeconds(5, [&] {
             stats = TraceStats();
             for (size_t i = 0; i < rays.size(); ++i)
               ours[i] = tracer.FirstHit(rays[i], stats).object;
           });
  r.visits = double(stats.nodeVisits) / n;
  double seconds;
  const std::vector<int32_t> theirs =
      EmbreeFirstHits(scene, rays, 5, &r.embreeBuild, &seconds, float(scene.camera.hither));
  r.embree = n / seconds;
  size_t agree = 0;
  for (size_t i = 0; i < rays.size(); ++i) agree += ours[i] == theirs[i];
  r.agree = double(agree) / n;
  return r;
}

// Rays per second on one core: the host tracer's FirstHit with --accel bvh (double, the
// hierarchy built before the clock starts) against Embree's rtcIntersect1 (float) on the
// primary rays of a size × size image of `count` grid spheres.
void BvhAgainstEmbree(int count, int size) {
  const Scene scene = GridSpheres(count, size);
  TraceOptions options;
  options.accel = Accel::kBvh;
  std::unique_ptr<Tracer> tracer;
  const double build = MedianSeconds(1, [&] { tracer = Tracer::Create(scene, options); });
  const RayRates r = NearestRates(scene, *tracer, ViewRays(scene));
  std::printf(
      "%6d grid spheres %4dx%-4d | ours (--accel bvh, double) %7.3f Mrays/s (build %.1f ms) | "
      "embree (float) %7.3f Mrays/s (build %.1f ms) | embree/ours %.2fx (target <= 4) | "
      "same object %.4f\n",
      count, size, size, r.ours * 1e-6, build * 1e3, r.embree * 1e-6, r.embreeBuild * 1e3,
      r.embree / r.ours, r.agree);
}

// Shadow rays from each point to each light beyond tMin: ours (LightThrough: the product of
// every surface crossed, so a ray through transparent spheres walks on) and Embree's
// rtcOccluded1 (any hit ends the ray: less work than ours, a bound).
RayRates ShadowRates(const Scene& scene, const Tracer& tracer, const std::vector<Vec3>& points,
                     double tMin) {
  RayRates r;
  const size_t lights = scene.lights.size();
  std::vector<uint8_t> ours(points.size() * lights), theirs(points.size() * lights);
  TraceStats stats;
  const double n = double(points.size() * lights);
  r.ours = n / MedianSeconds(5, [&] {
             stats = TraceStats();
             for (size_t i = 0; i < points.size(); ++i)
               for (size_t l = 0; l < lights; ++l)
                 ours[i * lights + l] = tracer.LightThrough(points[i], int(l), tMin, stats) < 1;
           });
  r.visits = double(stats.nodeVisits) / n;
  EmbreeSpheres es(scene);
  r.embree = n / MedianSeconds(5, [&] {
               RTCIntersectContext context;
               rtcInitIntersectContext(&context);
               for (size_t i = 0; i < points.size(); ++i)
                 for (size_t l = 0; l < lights; ++l) {
                   const Vec3 to = scene.lights[l].position - points[i];
                   const double dist = Length(to);
                   const Vec3 d = to / dist;
                   RTCRay ray{};
                   ray.org_x = float(points[i].x);
                   ray.org_y = float(points[i].y);
                   ray.org_z = float(points[i].z);
                   ray.dir_x = float(d.x);
                   ray.dir_y = float(d.y);
                   ray.dir_z = float(d.z);
                   ray.tnear = float(tMin);
                   ray.tfar = float(dist);
                   ray.mask = ~0u;
                   rtcOccluded1(es.scene, &context, &ray);
                   theirs[i * lights + l] = ray.tfar < 0;  // -inf when occluded
                 }
             });
  size_t agree = 0;
  for (size_t i = 0; i < ours.size(); ++i) agree += ours[i] == theirs[i];
  r.agree = double(agree) / n;
  return r;
}

// The seq render's rays by kind, ours and Embree's rates on one core: the primary rays of
// the size × size view of `count` random spheres (the seq line below), incoherent rays (as
// reflected and refracted rays are: from a point on each sphere in `perSphere` random
// directions) and shadow rays from those points to each light. Returns the rates so the
// seq line can say what the render's rays would take at Embree's.
struct SeqRayRates {
  RayRates primary, incoherent, shadow;
};
SeqRayRates SeqRaysAgainstEmbree(int count, int size, int perSphere) {
  const Scene scene = GenerateRandomSpheres({count, 1, size, size});
  TraceOptions options;
  options.accel = Accel::kBvh;
  const auto tracer = Tracer::Create(scene, options);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0, 1);
  std::vector<PrimaryRay> incoherent;
  std::vector<Vec3> points;
  for (const Primitive& p : scene.objects) {
    const Sphere& sp = std::get<Sphere>(p.shape);
    for (int k = 0; k < perSphere; ++k) {
      const Vec3 at = sp.centre + Normalize(Vec3{g(rng), g(rng), g(rng)}) * sp.radius;
      points.push_back(at);
      incoherent.push_back({at, Normalize(Vec3{g(rng), g(rng), g(rng)})});
    }
  }
  SeqRayRates r;
  r.primary = NearestRates(scene, *tracer, ViewRays(scene));
  r.incoherent = NearestRates(scene, *tracer, incoherent);
  r.shadow = ShadowRates(scene, *tracer, points, scene.camera.hither);
  const struct {
    const char* name;
    const RayRates& rate;
    const char* embree;
  } lines[] = {{"primary", r.primary, "rtcIntersect1"},
               {"incoherent", r.incoherent, "rtcIntersect1"},
               {"shadow", r.shadow, "rtcOccluded1"}};
  for (const auto& l : lines)
    std::printf(
        "%6d random spheres %dx%d, %-10s rays | ours (--accel bvh, double) %6.3f Mrays/s "
        "(%4.1f node visits a ray) | embree (float, %s) %6.3f Mrays/s | embree/ours %.2fx | "
        "same answer %.4f\n",
        count, size, size, l.name, l.rate.ours * 1e-6, l.rate.visits, l.embree,
        l.rate.embree * 1e-6, l.rate.embree / l.rate.ours, l.rate.agree);
  return r;
}

// seq's whole render (every ray of the tree, one core) of `count` random spheres at size ×
// size, with --accel none and --accel bvh (the build inside the clock), and whether the two
// images are the same bits; then what the render's rays alone would take at the rates of
// `rates` (primary rays at the primary rate, reflected and refracted at the incoherent,
// shadow at the shadow rate), ours and Embree's, and the ratio to --accel none that allows.
void SeqBvhAgainstExhaustive(int count, int size, int repeats, const SeqRayRates& rates) {
  const Scene scene = GenerateRandomSpheres({count, 1, size, size});
  std::vector<Vec3> pixels[2];
  double seconds[2];
  TraceStats stats;
  for (const Accel accel : {Accel::kNone, Accel::kBvh}) {
    TraceOptions options;
    options.accel = accel;
    const int k = accel == Accel::kBvh;
    seconds[k] = MedianSeconds(repeats, [&] {
      const auto tracer = Tracer::Create(scene, options);
      stats = TraceStats();
      RenderRegion(*tracer, 0, 0, size, size, pixels[k], stats);
    });
  }
  std::printf(
      "seq %d random spheres %dx%d: --accel none %.2f s, --accel bvh %.3f s: %.1fx faster "
      "(target >= 50), images %s (medians of %d)\n",
      count, size, size, seconds[0], seconds[1], seconds[0] / seconds[1],
      pixels[0].size() == pixels[1].size() &&
              std::memcmp(pixels[0].data(), pixels[1].data(), pixels[0].size() * sizeof(Vec3)) == 0
          ? "bit-identical"
          : "DIFFERENT",
      repeats);
  const double primary = double(stats.rays[int(RayKind::kPrimary)]);
  const double bounced =
      double(stats.rays[int(RayKind::kReflected)] + stats.rays[int(RayKind::kRefracted)]);
  const double shadow = double(stats.rays[int(RayKind::kShadow)]);
  const auto at = [&](double RayRates::*rate) {
    return primary / (rates.primary.*rate) + bounced / (rates.incoherent.*rate) +
           shadow / (rates.shadow.*rate);
  };
  std::printf(
      "seq's rays (%.0f primary, %.0f reflected or refracted, %.0f shadow) at the rates above, "
      "no shading: ours %.3f s, embree's %.3f s: --accel none / embree's rays alone = %.1fx\n",
      primary, bounced, shadow, at(&RayRates::ours), at(&RayRates::embree),
      seconds[0] / at(&RayRates::embree));
}

}  // namespace
}  // namespace zephyr

int main() {
  std::printf(
      "bench_trace: primary rays of `zephyr gen spheres`, nearest hit (Hearn-Baker), one core, "
      "medians of 5; Gt/s = 10^9 ray-sphere tests/s; kernel = hosts/sphere_kernels (%s), "
      "'exact' = same object and t bits as the scalar loop on every ray\n",
      zephyr::SphereKernelTargetName());
  for (int count : {10, 100, 1000}) zephyr::Run(count, count >= 1000 ? 128 : 256);
  std::printf(
      "bench_trace: the host tracer's BVH against Embree, one core, medians of 5: primary rays "
      "of grid spheres; the seq scene's primary, incoherent and shadow rays; seq's render\n");
  for (int count : {1000, 100000}) zephyr::BvhAgainstEmbree(count, 384);
  const zephyr::SeqRayRates rates = zephyr::SeqRaysAgainstEmbree(4096, 384, 64);
  zephyr::SeqBvhAgainstExhaustive(4096, 384, 3, rates);
  return 0;
}
