// hosts/simd/direction.h — a primary direction as the SIMD pass's matrix holds it, written
// once for both sides that need it: the pass (which loads the quantised components onto
// the array and decodes the matrix on the host) and the heterogeneous method's children
// (which recompute each pixel's direction instead of receiving it; docs/distributed.md).
#pragma once

#include <cmath>
#include <cstdint>

#include "hosts/scene/geometry.h"

namespace zephyr::simd {

// One direction component as the array holds it: round(c · 2^dirFracBits), the raw value
// of the s1.dirFracBits direction format (docs/simd.md, "The matrix layout").
inline std::int64_t QuantiseDirection(double component, int dirFracBits) {
  return std::llround(std::ldexp(component, dirFracBits));
}

// The host's decoding of the matrix's three raw direction components: scaled back by
// 2^-dirFracBits and renormalised in double.
inline Vec3 DecodeDirection(std::int64_t x, std::int64_t y, std::int64_t z, int dirFracBits) {
  return Normalize(Vec3{std::ldexp(double(x), -dirFracBits), std::ldexp(double(y), -dirFracBits),
                        std::ldexp(double(z), -dirFracBits)});
}

// The direction the matrix holds for the exact eye-ray direction `exact` (a pixel the pass
// did not recompute on the host).
inline Vec3 MatrixDirection(const Vec3& exact, int dirFracBits) {
  return DecodeDirection(QuantiseDirection(exact.x, dirFracBits),
                         QuantiseDirection(exact.y, dirFracBits),
                         QuantiseDirection(exact.z, dirFracBits), dirFracBits);
}

}  // namespace zephyr::simd
