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
#include <optional>
#include <string>
#include <vector>

#include "bitserial/report.h"
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

// One array pass (docs/simd.md, "Several array passes"): its run of the program's cycle
// report, the memory it used per virtual PE (peak and capacity, bits), its wall time on this
// host (seconds), and the plan's virtual PEs it ran (firstPe .. firstPe + pes - 1).
struct ArrayPassReport {
  bitserial::CycleReport cycles;
  int64_t internalPeakBits = 0, internalCapacityBits = 0;
  int64_t externalPeakBits = 0, externalCapacityBits = 0;
  double hostSeconds = 0;
  int64_t firstPe = 0, pes = 0;
};

// Every array pass of one run of the program (the first pass's, or the refine pass's):
// each pass's report, their sum, and the wall time of them all (seconds).
struct ArrayRunReport {
  std::vector<ArrayPassReport> passes;
  bitserial::CycleReport cycles;  // every pass's, summed (bitserial::CycleReport::Add)
  double hostSeconds = 0;
  // The passes hold whole image rows of this width (the first pass), or 0 (the refine pass:
  // compacted pixels); for the table's "rows a..b".
  int rowWidth = 0;
  double ModelledSeconds() const { return cycles.ModelledSeconds(); }
  // The printable cycle report: one pass's table, or each pass's and the total.
  std::string Table() const;
};

// The first pass's uncertain pixels by cause (a pixel may have several).
struct UncertainCounts {
  int64_t overflow = 0, grazing = 0, nearTie = 0;
};

// --uncertain refine (or auto over budget): the refine pass over the uncertain pixels,
// compacted (docs/simd.md, "Refine pass").
struct RefineResult {
  int64_t pixels = 0;  // the pixels it ran on
  int layers = 0;      // virtual-PE layers of its plan
  int fracBits = 0, dirFracBits = 0;
  double tErrorBound = 0;      // its plan's bound on t (scene units)
  int64_t stillUncertain = 0;  // pixels it could not certify (then recomputed on the host)
  UncertainCounts uncertain;   // of those, by cause
  ArrayRunReport array;
};

struct PrimaryPass {
  PrimaryPlan plan;
  PrimaryMatrix matrix;
  ArrayRunReport array;         // the first pass on the array: cycles, passes, wall time
  double recomputeSeconds = 0;  // the host's part after the array: decode, refine, recompute
  // The first pass's uncertain pixels (by cause), and how many the host recomputed.
  UncertainCounts uncertain;
  int64_t recomputedPixels = 0;
  // What that recompute counted (one primary ray a pixel; every object's test, or with
  // SimdOptions::hostAccel = kBvh the hierarchy's tests, node visits, box tests and build):
  // the host work the testbed prices for it (testbed::RecomputeWork).
  TraceStats recomputeWork;
  std::optional<RefineResult> refine;  // when a refine pass ran
  int64_t RefinedPixels() const { return refine ? refine->pixels : 0; }
};

// Fraction bits the refine pass adds to the planned widths (docs/simd.md, "Refine pass").
inline constexpr int kRefineExtraBits = 8;

// The array part of the method: every primary ray's first hit, with the uncertain pixels
// handled by options.uncertain (kFail throws UserError with the counts).
PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options);
// The same on a plan the caller has made with PlanPrimaryPass(scene, options) (to check what
// follows the pass before running it: the array method's bounce programs).
PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options, PrimaryPlan plan);

// Host shading of the w×h rectangle at (x0, y0) from the matrix (linear RGB, row-major).
void ShadeRegion(const Tracer& tracer, const PrimaryMatrix& matrix, int x0, int y0, int w, int h,
                 std::vector<Vec3>& out, TraceStats& stats);

}  // namespace zephyr::simd
