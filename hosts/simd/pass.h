// hosts/simd/pass.h — the SIMD/sequential method (paper §3, SPEC §1): primary rays on the
// emulated array in fixed point, the per-pixel matrix, host shading from it.
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

#include "bitserial/profile.h"
#include "fixed/format.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
struct RenderOptions;  // hosts/methods/render.h
}

namespace zephyr::simd {

// What to do with uncertain pixels (overflow, grazing, near tie).
enum class UncertainPolicy { kRecompute, kKeep, kFail };
UncertainPolicy ParseUncertainPolicy(const std::string& name);  // recompute|keep|fail
const char* UncertainPolicyName(UncertainPolicy p);

// Per-pixel flag bits (--dump-primary's flags column).
enum PixelFlag : uint32_t {
  kOverflow = 1u << 0,    // some fixed-point result did not fit its format
  kGrazing = 1u << 1,     // a discriminant within its error bound of zero
  kNearTie = 1u << 2,     // two objects' t within the error bound of each other
  kRecomputed = 1u << 3,  // the host recomputed the pixel in double
};

// User overrides of the planner (negative = the planner chooses).
struct FormatOverrides {
  int fracBits = -1;     // --frac-bits: fraction bits of lengths, t and directions
  int dirFracBits = -1;  // --dir-frac-bits: fraction bits of the direction components only
  int intBits = -1;      // --int-bits: integer bits of distances
};

struct SimdOptions {
  std::string profile = "wavetracer";
  std::vector<std::string> profileOverrides;  // "readExternal=3", ...
  FormatOverrides formats;
  UncertainPolicy uncertain = UncertainPolicy::kRecompute;
};

// One chosen quantity of the plan: its format and why.
struct PlannedFormat {
  std::string quantity;
  fixed::Format format;
  std::string reason;
};

// The format planner's choice for one scene (SPEC §4: model no more than a scene needs).
struct PrimaryPlan {
  int width = 0, height = 0;
  int64_t virtualPes = 0;
  int layers = 0;
  int distIntBits = 0;      // integer bits of every distance (eye-to-object, t)
  int fracBits = 0;         // fraction bits of lengths, products, discriminants, t
  int dirFracBits = 0;      // fraction bits of the direction components
  int objectBits = 0;       // width of the object index (+1, 0 = none)
  fixed::Format direction, length, t, object;
  double tErrorBound = 0;   // |t_fixed − t_exact| for a certain (unflagged) hit: the largest
                            // per-object bound (always-uncertain objects excluded)
  double grazingFraction = 0;  // grazing band G = max((r·this)², 2·e_disc), per object
  std::vector<PlannedFormat> formats;
  int64_t memoryBitsPerPe = 0;  // peak estimate per virtual PE
  int64_t matrixBitsPerPe = 0;  // the per-pixel matrix in external memory
  int64_t internalCapacity = 0, externalCapacity = 0;  // bits per virtual PE
  int alwaysUncertainObjects = 0;  // objects whose bounds degenerate at these widths (every
                                   // pixel that may hit them is flagged)
  nlohmann::json Json() const;
  std::string Text() const;  // `zephyr plan`'s output
};

// Throws UserError when no format within the machine's memory can hold the scene.
PrimaryPlan PlanPrimaryPass(const Scene& scene, const SimdOptions& options);

// The per-pixel matrix, row-major: first object (-1: none), t, unit direction, flags.
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
  int64_t overflowPixels = 0, grazingPixels = 0, tiePixels = 0, recomputedPixels = 0;
  nlohmann::json Json() const;  // everything above but the matrix
};

// The simd flags of a render command (--frac-bits, --dir-frac-bits, --int-bits,
// --uncertain, --machine) from RenderOptions::extra; UserError on a bad value.
SimdOptions SimdOptionsFrom(const RenderOptions& options);

// The array part of the method: every primary ray's first hit, with the uncertain pixels
// handled by options.uncertain (kFail throws UserError with the counts).
PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options);

// Host shading of the w×h rectangle at (x0, y0) from the matrix (linear RGB, row-major).
void ShadeRegion(const Tracer& tracer, const PrimaryMatrix& matrix, int x0, int y0, int w,
                 int h, std::vector<Vec3>& out, TraceStats& stats);

}  // namespace zephyr::simd
