// hosts/simd/pass.h — the SIMD/sequential method (paper §3): primary rays on the
// emulated array in fixed point, the per-pixel matrix, host shading from it. The planner
// (hosts/simd/plan.h) chooses every format and bound the pass runs with.
//
//   simd::PrimaryPass pass = simd::RunPrimaryPass(scene, simdOptions);   // the array part
//   simd::ShadeRegion(*tracer, pass.matrix, x0, y0, w, h, pixels, stats);  // the host part
//
// ShadeRegion gives, for any rectangle, exactly the pixels `zephyr render --method simd`
// gives for it (the heterogeneous method shades frames from the matrix this way).
// docs/simd.md describes the program, the matrix layout, the planner and the flags.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hosts/scene/scene.h"
#include "hosts/simd/plan.h"
#include "hosts/trace/tracer.h"

namespace zephyr::simd {

// Per-pixel flag bits (--dump-primary's flags column).
enum PixelFlag : uint32_t {
  kOverflow = 1u << 0,    // some fixed-point result did not fit its format
  kGrazing = 1u << 1,     // a discriminant within its error bound of zero
  kNearTie = 1u << 2,     // two objects' t within the error bound of each other
  kRecomputed = 1u << 3,  // the host recomputed the pixel in double
  // The refine pass certified the pixel (--uncertain refine): its t and direction are the
  // refine pass's, the direction quantised at that pass's dirFracBits (docs/simd.md, "Refine
  // pass"). Not an uncertainty: kUncertainFlags leaves it out.
  kRefined = 1u << 4,
};
// The flags that make a pixel uncertain (recomputed, refined, kept or failed by the policy).
inline constexpr uint32_t kUncertainFlags = kOverflow | kGrazing | kNearTie;

// The per-pixel matrix, row-major: first object (-1: none), t, unit direction, flags. A pixel's
// t is along its own direction: the first pass's quantised one, the refine pass's for a pixel
// it certified (kRefined), the eye ray for one the host recomputed (kRecomputed).
struct PrimaryMatrix {
  int width = 0, height = 0;
  std::vector<PrimaryHit> hits;
  std::vector<uint32_t> flags;
};

struct PrimaryPass {
  PrimaryPlan plan;
  PrimaryMatrix matrix;
  nlohmann::json cycles;      // bitserial::CycleReport::Json() plus memory and timing
  std::string cycleTable;     // the printable cycle report
  double hostSeconds = 0;     // wall time of the emulated pass (array part)
  double modelledSeconds = 0; // at the profile's clock
  double recomputeSeconds = 0;
  // The first pass's uncertain pixels (by cause), and how many the host recomputed.
  int64_t overflowPixels = 0, grazingPixels = 0, tiePixels = 0, recomputedPixels = 0;
  // --uncertain refine: the pixels the refine pass ran on (0: none ran), and its report
  // (pixels, layers, formats, stillUncertain and its causes, cycles, timing; null if none).
  int64_t refinedPixels = 0;
  nlohmann::json refine;
  std::string refineCycleTable;
  nlohmann::json Json() const;  // everything above but the matrix and the tables
};

// Fraction bits the refine pass adds to the planned widths (docs/simd.md, "Refine pass").
inline constexpr int kRefineExtraBits = 8;

// The array part of the method: every primary ray's first hit, with the uncertain pixels
// handled by options.uncertain (kFail throws UserError with the counts).
PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options);

// Host shading of the w×h rectangle at (x0, y0) from the matrix (linear RGB, row-major).
void ShadeRegion(const Tracer& tracer, const PrimaryMatrix& matrix, int x0, int y0, int w,
                 int h, std::vector<Vec3>& out, TraceStats& stats);

}  // namespace zephyr::simd
