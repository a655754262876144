// hosts/methods/hetero_entry.h — hetero's per-pixel matrix entry on the wire (docs/distributed.md).
//
// A hetero work message carries, for each pixel of the frame, only what a child cannot
// recompute: the first object, t as the shader starts from it, and the flags. The primary
// direction is recomputed by the child from the pixel's (x, y), the camera and the plan's
// direction fraction bits with the pass's own quantisation (hosts/simd/direction.h).
//
//   hetero::PutEntry(pass.matrix.hits[i], pass.matrix.flags[i], bytes);      // parent
//   PrimaryHit hit = hetero::GetEntry(bytes, objectCount, flags);             // child
//   hit.direction = hetero::MatrixDirection(rays, x, y, dirFracBits, flags);
#pragma once

#include <cstddef>
#include <cstdint>

#include "hosts/trace/tracer.h"

namespace zephyr::hetero {

// i32 object (-1: none), u8 flags (simd::PixelFlag bits), f64 t (0 for a miss).
inline constexpr std::size_t kEntryBytes = 13;

void PutEntry(const PrimaryHit& hit, std::uint32_t flags, std::byte* at);

// The entry's object, t and flags (the direction is left zero). UserError ("malformed work
// message: …") for an object outside the scene, unknown flag bits, a t that is not finite,
// or a miss with a non-zero t.
PrimaryHit GetEntry(const std::byte* at, int objectCount, std::uint32_t& flags);

// The direction the SIMD pass's matrix holds for pixel (x, y): the eye ray quantised to
// dirFracBits fraction bits on the array and renormalised on the host; for a pixel the refine
// pass certified (simd::kRefined), quantised to the refine pass's refineDirFracBits instead
// (UserError "malformed work message" if that is negative: no refine pass ran); for a pixel
// the host recomputed in double (simd::kRecomputed), the eye ray itself.
Vec3 MatrixDirection(const PrimaryRays& rays, int x, int y, int dirFracBits, int refineDirFracBits,
                     std::uint32_t flags);

}  // namespace zephyr::hetero
