// hosts/trace/sphere_kernels.cpp — compiled once per Highway target (foreach_target.h).
//
// Bit-exactness with the scalar IntersectSphere across targets needs the same roundings in
// the same order: no a·b + c fused into one FMA on the targets that have FMA (GCC contracts
// Mul+Add intrinsics by default), hence fp-contract off for everything in this file.
#if defined(__clang__)
#pragma clang fp contract(off)
#else
#pragma GCC optimize("fp-contract=off")
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hosts/trace/sphere_kernels.cpp"
#include "hosts/trace/sphere_kernels.h"

#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace zephyr::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// One vector of spheres against the ray: lanes in `live` whose first root in (tMin, inf) is
// strictly nearer than best[lane] take it, with their index. Every step mirrors
// IntersectSphereHearnBaker / IntersectSphereNaive and KeepRoots (trace_intersect.h),
// including their treatment of NaN (a comparison that is false does not reject).
template <bool kHearnBaker, class D, class V = hn::Vec<D>, class M = hn::Mask<D>,
          class VI = hn::Vec<hn::RebindToSigned<D>>>
HWY_INLINE void SphereBlock(D d, M live, V cx, V cy, V cz, V rr, const V (&ray)[7], V& best,
                            VI& bestIndex, VI index) {
  const V zero = hn::Zero(d);
  const V &ox = ray[0], &oy = ray[1], &oz = ray[2], &dx = ray[3], &dy = ray[4], &dz = ray[5];
  const V& tMin = ray[6];
  // f = o − centre; b = −(f·d)
  const V fx = hn::Sub(ox, cx), fy = hn::Sub(oy, cy), fz = hn::Sub(oz, cz);
  const V b = hn::Neg(hn::Add(hn::Add(hn::Mul(fx, dx), hn::Mul(fy, dy)), hn::Mul(fz, dz)));
  V t0, t1, disc;
  if constexpr (kHearnBaker) {
    // v = f + d·b; disc = r² − v·v
    const V vx = hn::Add(fx, hn::Mul(dx, b)), vy = hn::Add(fy, hn::Mul(dy, b)),
            vz = hn::Add(fz, hn::Mul(dz, b));
    disc = hn::Sub(rr, hn::Add(hn::Add(hn::Mul(vx, vx), hn::Mul(vy, vy)), hn::Mul(vz, vz)));
    live = hn::AndNot(hn::Lt(disc, zero), live);
    if (hn::AllFalse(d, live)) return;  // the common case: skip the sqrt and the division
    const V c = hn::Sub(hn::Add(hn::Add(hn::Mul(fx, fx), hn::Mul(fy, fy)), hn::Mul(fz, fz)), rr);
    const V q = hn::Add(b, hn::CopySign(hn::Sqrt(disc), b));
    live = hn::And(live, hn::Ne(q, zero));  // grazing the eye itself
    t0 = hn::Div(c, q);
    t1 = q;
  } else {
    // c = f·f − r²; disc = b² − c
    const V c = hn::Sub(hn::Add(hn::Add(hn::Mul(fx, fx), hn::Mul(fy, fy)), hn::Mul(fz, fz)), rr);
    disc = hn::Sub(hn::Mul(b, b), c);
    live = hn::AndNot(hn::Lt(disc, zero), live);
    if (hn::AllFalse(d, live)) return;
    const V s = hn::Sqrt(disc);
    t0 = hn::Sub(b, s);
    t1 = hn::Add(b, s);
  }
  // KeepRoots: order the pair (swap only when t0 > t1), the first beyond tMin is the root.
  const M swap = hn::Gt(t0, t1);
  const V lo = hn::IfThenElse(swap, t1, t0), hi = hn::IfThenElse(swap, t0, t1);
  const M loOk = hn::Gt(lo, tMin);
  live = hn::And(live, hn::Or(loOk, hn::Gt(hi, tMin)));
  const V root = hn::IfThenElse(loOk, lo, hi);
  const M take = hn::And(live, hn::Lt(root, best));
  best = hn::IfThenElse(take, root, best);
  bestIndex = hn::IfThenElse(hn::RebindMask(hn::RebindToSigned<D>(), take), index, bestIndex);
}

template <bool kHearnBaker, typename T>
int32_t NearestSphereForm(const T* HWY_RESTRICT cx, const T* HWY_RESTRICT cy,
                          const T* HWY_RESTRICT cz, const T* HWY_RESTRICT r2, size_t n,
                          const T* rayIn, T* tOut) {
  const hn::ScalableTag<T> d;
  const hn::RebindToSigned<decltype(d)> di;
  using V = hn::Vec<decltype(d)>;
  using I = hn::TFromD<decltype(di)>;
  const size_t lanes = hn::Lanes(d);
  const V ray[7] = {hn::Set(d, rayIn[0]), hn::Set(d, rayIn[1]), hn::Set(d, rayIn[2]),
                    hn::Set(d, rayIn[3]), hn::Set(d, rayIn[4]), hn::Set(d, rayIn[5]),
                    hn::Set(d, rayIn[6])};
  V best = hn::Set(d, std::numeric_limits<T>::infinity());
  auto bestIndex = hn::Set(di, I(-1));
  auto index = hn::Iota(di, 0);
  const auto step = hn::Set(di, I(lanes));
  const auto all = hn::FirstN(d, lanes);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    SphereBlock<kHearnBaker>(d, all, hn::LoadU(d, cx + i), hn::LoadU(d, cy + i),
                             hn::LoadU(d, cz + i), hn::LoadU(d, r2 + i), ray, best, bestIndex,
                             index);
    index = hn::Add(index, step);
  }
  if (i < n) {  // the remainder under a mask; the other lanes are off
    const auto live = hn::FirstN(d, n - i);
#if HWY_TARGET <= HWY_AVX2
    // Masked loads that do not touch the lanes beyond n (vmaskmov / AVX-512 masking).
    SphereBlock<kHearnBaker>(d, live, hn::MaskedLoad(live, d, cx + i),
                             hn::MaskedLoad(live, d, cy + i), hn::MaskedLoad(live, d, cz + i),
                             hn::MaskedLoad(live, d, r2 + i), ray, best, bestIndex, index);
#else
    // Older targets' MaskedLoad reads the whole vector: copy into a vector-sized buffer.
    HWY_ALIGN T tail[4][hn::MaxLanes(d)] = {};
    for (size_t k = 0; i + k < n; ++k) {
      tail[0][k] = cx[i + k];
      tail[1][k] = cy[i + k];
      tail[2][k] = cz[i + k];
      tail[3][k] = r2[i + k];
    }
    SphereBlock<kHearnBaker>(d, live, hn::Load(d, tail[0]), hn::Load(d, tail[1]),
                             hn::Load(d, tail[2]), hn::Load(d, tail[3]), ray, best, bestIndex,
                             index);
#endif
  }
  *tOut = std::numeric_limits<T>::infinity();
  if (hn::AllTrue(di, hn::Lt(bestIndex, hn::Zero(di)))) return -1;  // the common miss
  // Across lanes: the smallest t, and among equal t the lowest index (as the scalar loop).
  HWY_ALIGN T bt[hn::MaxLanes(d)];
  HWY_ALIGN I bi[hn::MaxLanes(di)];
  hn::Store(best, d, bt);
  hn::Store(bestIndex, di, bi);
  I found = -1;
  T tBest = std::numeric_limits<T>::infinity();
  for (size_t k = 0; k < lanes; ++k) {
    if (bi[k] >= 0 && (bt[k] < tBest || (bt[k] == tBest && bi[k] < found))) {
      tBest = bt[k];
      found = bi[k];
    }
  }
  *tOut = tBest;
  return int32_t(found);
}

// ray = {ox, oy, oz, dx, dy, dz, tMin}
int32_t NearestSphereF32(int hearnBaker, const float* cx, const float* cy, const float* cz,
                         const float* r2, size_t n, const float* ray, float* t) {
  return hearnBaker ? NearestSphereForm<true>(cx, cy, cz, r2, n, ray, t)
                    : NearestSphereForm<false>(cx, cy, cz, r2, n, ray, t);
}
int32_t NearestSphereF64(int hearnBaker, const double* cx, const double* cy, const double* cz,
                         const double* r2, size_t n, const double* ray, double* t) {
  return hearnBaker ? NearestSphereForm<true>(cx, cy, cz, r2, n, ray, t)
                    : NearestSphereForm<false>(cx, cy, cz, r2, n, ray, t);
}

}  // namespace zephyr::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zephyr {

HWY_EXPORT(NearestSphereF32);
HWY_EXPORT(NearestSphereF64);

namespace {
template <typename T, typename Kernel>
int32_t Call(Kernel* kernel, SphereTest form, const SphereArrays<T>& s, const Vec3T<T>& o,
             const Vec3T<T>& d, T tMin, T* t) {
  const T ray[7] = {o.x, o.y, o.z, d.x, d.y, d.z, tMin};
  return kernel(form == SphereTest::kHearnBaker, s.cx.data(), s.cy.data(), s.cz.data(), s.r2.data(),
                s.Size(), ray, t);
}
}  // namespace

int32_t NearestSphere(SphereTest form, const SphereArrays<float>& s, const Vec3T<float>& o,
                      const Vec3T<float>& d, float tMin, float* t) {
  return Call(&HWY_DYNAMIC_DISPATCH(NearestSphereF32), form, s, o, d, tMin, t);
}
int32_t NearestSphere(SphereTest form, const SphereArrays<double>& s, const Vec3T<double>& o,
                      const Vec3T<double>& d, double tMin, double* t) {
  return Call(&HWY_DYNAMIC_DISPATCH(NearestSphereF64), form, s, o, d, tMin, t);
}

const char* SphereKernelTargetName() {
  // HWY_DYNAMIC_DISPATCH picks the best (lowest-valued bit) target supported and compiled.
  const int64_t targets = hwy::SupportedTargets() & HWY_TARGETS;
  return hwy::TargetName(targets & -targets);
}

}  // namespace zephyr
#endif  // HWY_ONCE
