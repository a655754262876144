// hosts/trace/sphere_kernels.h — the nearest of many spheres along one ray, many spheres per
// vector (Highway, run-time dispatch; compiled once per target in sphere_kernels.cpp).
//
// Contract: the result is bit-identical to NearestSphereScalar — the plain loop over
// IntersectSphere (trace_intersect.h) that keeps a root when it is strictly nearer — on every
// dispatch target: the kernels perform the same IEEE operations in the same order (no FMA:
// the file is compiled with fp-contract off), so the object and the bits of t agree, and
// ties between equal t go to the lowest index. The distributed methods rely on seq being
// bit-reproducible whatever the machine picks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "hosts/scene/geometry.h"
#include "hosts/trace/intersect.h"

namespace zephyr {

// Untransformed spheres in structure-of-arrays form (centre, squared radius).
template <typename T>
struct SphereArrays {
  std::vector<T> cx, cy, cz, r2;

  void Push(const Vec3T<T>& centre, T radius2) {
    cx.push_back(centre.x);
    cy.push_back(centre.y);
    cz.push_back(centre.z);
    r2.push_back(radius2);
  }
  size_t Size() const { return cx.size(); }
};

// The sphere whose first root along o + t·d in (tMin, +inf) is nearest (d unit length), in
// the given form: its index in `spheres` (-1 when none) and that root in *t (+inf when none).
// One dispatch per call; full vectors, then the remainder under a mask.
int32_t NearestSphere(SphereTest form, const SphereArrays<float>& spheres, const Vec3T<float>& o,
                      const Vec3T<float>& d, float tMin, float* t);
int32_t NearestSphere(SphereTest form, const SphereArrays<double>& spheres, const Vec3T<double>& o,
                      const Vec3T<double>& d, double tMin, double* t);

// The reference the kernels must match bit for bit: one sphere at a time.
template <typename T>
int32_t NearestSphereScalar(SphereTest form, const SphereArrays<T>& s, const Vec3T<T>& o,
                            const Vec3T<T>& d, T tMin, T* t) {
  T best = std::numeric_limits<T>::infinity();
  int32_t found = -1;
  T roots[2];
  for (size_t i = 0; i < s.Size(); ++i) {
    if (IntersectSphere(form, o, d, {s.cx[i], s.cy[i], s.cz[i]}, s.r2[i], tMin, roots) > 0 &&
        roots[0] < best) {
      best = roots[0];
      found = int32_t(i);
    }
  }
  *t = best;
  return found;
}

// The Highway target NearestSphere dispatches to now (for benchmarks and reports).
const char* SphereKernelTargetName();

}  // namespace zephyr
