// LIBS: -lembree3
// tools/bench/trace.cpp — ray–sphere tests per second on one core: the plain scalar loop,
// the Highway-vectorised loop (many spheres per vector, Hearn–Baker form, float), and
// Embree 3's BVH with its built-in sphere primitive tracing the same primary rays, for
// 10, 100 and 1000 spheres (issue 4). Prints medians of repeats.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "tools/bench/trace.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

HWY_BEFORE_NAMESPACE();
namespace zephyr {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The nearest sphere along one ray (unit d) among n spheres in structure-of-arrays form,
// n a multiple of the vector length (padding has r2 = -1: never hit). Returns the index or
// -1 and writes t.
int32_t NearestSphere(const float* HWY_RESTRICT cx, const float* HWY_RESTRICT cy,
                      const float* HWY_RESTRICT cz, const float* HWY_RESTRICT r2, size_t n,
                      const float* ray, float* tOut) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  const size_t lanes = hn::Lanes(d);
  const auto ox = hn::Set(d, ray[0]), oy = hn::Set(d, ray[1]), oz = hn::Set(d, ray[2]);
  const auto dx = hn::Set(d, ray[3]), dy = hn::Set(d, ray[4]), dz = hn::Set(d, ray[5]);
  const auto zero = hn::Zero(d);
  auto best = hn::Set(d, std::numeric_limits<float>::infinity());
  auto bestIndex = hn::Set(di, -1);
  auto index = hn::Iota(di, 0);
  const auto step = hn::Set(di, int32_t(lanes));
  for (size_t i = 0; i < n; i += lanes) {
    const auto fx = hn::Sub(ox, hn::LoadU(d, cx + i));
    const auto fy = hn::Sub(oy, hn::LoadU(d, cy + i));
    const auto fz = hn::Sub(oz, hn::LoadU(d, cz + i));
    const auto rr = hn::LoadU(d, r2 + i);
    const auto b = hn::Neg(hn::MulAdd(fx, dx, hn::MulAdd(fy, dy, hn::Mul(fz, dz))));
    const auto vx = hn::MulAdd(b, dx, fx), vy = hn::MulAdd(b, dy, fy), vz = hn::MulAdd(b, dz, fz);
    const auto disc = hn::Sub(rr, hn::MulAdd(vx, vx, hn::MulAdd(vy, vy, hn::Mul(vz, vz))));
    const auto c = hn::Sub(hn::MulAdd(fx, fx, hn::MulAdd(fy, fy, hn::Mul(fz, fz))), rr);
    const auto q = hn::Add(b, hn::CopySign(hn::Sqrt(hn::Max(disc, zero)), b));
    const auto t0 = hn::Div(c, q);
    const auto near = hn::Min(t0, q), far = hn::Max(t0, q);
    const auto t = hn::IfThenElse(hn::Gt(near, zero), near, far);
    const auto take = hn::And(hn::And(hn::Ge(disc, zero), hn::Gt(t, zero)), hn::Lt(t, best));
    best = hn::IfThenElse(take, t, best);
    bestIndex = hn::IfThenElse(hn::RebindMask(di, take), index, bestIndex);
    index = hn::Add(index, step);
  }
  HWY_ALIGN float bt[hn::MaxLanes(d)];
  HWY_ALIGN int32_t bi[hn::MaxLanes(di)];
  hn::Store(best, d, bt);
  hn::Store(bestIndex, di, bi);
  int32_t found = -1;
  float tBest = std::numeric_limits<float>::infinity();
  for (size_t k = 0; k < lanes; ++k) {
    if (bi[k] >= 0 && (bt[k] < tBest || (bt[k] == tBest && bi[k] < found))) {
      tBest = bt[k];
      found = bi[k];
    }
  }
  *tOut = tBest;
  return found;
}

}  // namespace HWY_NAMESPACE
}  // namespace zephyr
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <embree3/rtcore.h>

#include "hosts/trace.h"
#include "tools/gen.h"

namespace zephyr {
HWY_EXPORT(NearestSphere);

namespace {

struct SoA {
  std::vector<float> cx, cy, cz, r2;
  size_t n = 0;
};

SoA Pack(const Scene& s) {
  SoA a;
  a.n = s.objects.size();
  const size_t padded = (a.n + 15) / 16 * 16;  // a multiple of every x86 float vector length
  a.cx.assign(padded, 0);
  a.cy.assign(padded, 0);
  a.cz.assign(padded, 0);
  a.r2.assign(padded, -1);
  for (size_t i = 0; i < a.n; ++i) {
    const auto& sp = std::get<Sphere>(s.objects[i].shape);
    a.cx[i] = float(sp.center.x);
    a.cy[i] = float(sp.center.y);
    a.cz[i] = float(sp.center.z);
    a.r2[i] = float(sp.radius * sp.radius);
  }
  return a;
}

int32_t NearestScalar(const SoA& a, const float* ray, float* tOut) {
  const Vec3T<float> o{ray[0], ray[1], ray[2]}, d{ray[3], ray[4], ray[5]};
  float best = std::numeric_limits<float>::infinity();
  int32_t found = -1;
  float roots[2];
  for (size_t i = 0; i < a.n; ++i) {
    if (IntersectSphereHearnBaker<float>(o, d, {a.cx[i], a.cy[i], a.cz[i]}, a.r2[i], 0.0f, roots) > 0 &&
        roots[0] < best) {
      best = roots[0];
      found = int32_t(i);
    }
  }
  *tOut = best;
  return found;
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

volatile int64_t sink;

// The target HWY_DYNAMIC_DISPATCH picks: the best (lowest-valued bit) supported and compiled.
const char* BestTargetName() {
  const int64_t targets = hwy::SupportedTargets() & HWY_TARGETS;
  return hwy::TargetName(targets & -targets);
}

void Run(int count, int size) {
  const Scene scene = GenerateRandomSpheres({count, 1, size, size});
  const SoA soa = Pack(scene);
  const PrimaryRays rays(scene.camera);
  std::vector<float> packed;  // o, d per ray
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const PrimaryRay r = rays.At(x, y);
      for (double v : {r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z})
        packed.push_back(float(v));
    }
  }
  const size_t nRays = packed.size() / 6;
  std::vector<int32_t> scalarHit(nRays), simdHit(nRays), embreeHit(nRays);
  const double tests = double(nRays) * count;
  const int repeats = 5;

  const double scalar = MedianSeconds(repeats, [&] {
    float t;
    for (size_t i = 0; i < nRays; ++i) scalarHit[i] = NearestScalar(soa, &packed[6 * i], &t);
  });
  const double simd = MedianSeconds(repeats, [&] {
    float t;
    for (size_t i = 0; i < nRays; ++i)
      simdHit[i] = HWY_DYNAMIC_DISPATCH(NearestSphere)(soa.cx.data(), soa.cy.data(), soa.cz.data(),
                                                       soa.r2.data(), soa.cx.size(), &packed[6 * i], &t);
  });

  RTCDevice device = rtcNewDevice("threads=1");
  RTCScene es = rtcNewScene(device);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                        4 * sizeof(float), size_t(count)));
  for (int i = 0; i < count; ++i) {
    v[4 * i] = soa.cx[i];
    v[4 * i + 1] = soa.cy[i];
    v[4 * i + 2] = soa.cz[i];
    v[4 * i + 3] = std::sqrt(soa.r2[i]);
  }
  rtcCommitGeometry(g);
  rtcAttachGeometry(es, g);
  rtcReleaseGeometry(g);
  const double build = MedianSeconds(1, [&] { rtcCommitScene(es); });
  const double embree = MedianSeconds(repeats, [&] {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = 0; i < nRays; ++i) {
      RTCRayHit rh{};
      const float* r = &packed[6 * i];
      rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
      rh.ray.dir_x = r[3]; rh.ray.dir_y = r[4]; rh.ray.dir_z = r[5];
      rh.ray.tnear = 0;
      rh.ray.tfar = std::numeric_limits<float>::infinity();
      rh.ray.mask = ~0u;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(es, &context, &rh);
      embreeHit[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : int32_t(rh.hit.primID);
    }
  });
  rtcReleaseScene(es);
  rtcReleaseDevice(device);

  size_t simdAgree = 0, embreeAgree = 0;
  for (size_t i = 0; i < nRays; ++i) {
    simdAgree += simdHit[i] == scalarHit[i];
    embreeAgree += embreeHit[i] == scalarHit[i];
  }
  sink = simdAgree;
  std::printf("%6d spheres %4dx%-4d | scalar %7.3f ms %7.3f Gtests/s | highway(%s) %7.3f ms %7.3f Gtests/s "
              "x%.1f | embree %7.3f ms (+build %.3f ms) = %7.3f Gtests/s-equiv | agree: hwy %.4f embree %.4f\n",
              count, size, size, scalar * 1e3, tests / scalar * 1e-9,
              BestTargetName(), simd * 1e3,
              tests / simd * 1e-9, scalar / simd, embree * 1e3, build * 1e3, tests / embree * 1e-9,
              double(simdAgree) / nRays, double(embreeAgree) / nRays);
}

}  // namespace
}  // namespace zephyr

int main() {
  std::printf("bench_trace: primary rays of `zephyr gen spheres`, nearest hit, one core, medians of 5\n");
  for (int count : {10, 100, 1000}) zephyr::Run(count, count >= 1000 ? 128 : 256);
  return 0;
}
#endif  // HWY_ONCE
