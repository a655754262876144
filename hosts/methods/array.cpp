// hosts/methods/array.cpp — every ray on the array (the fifth method; docs/wavefront.md): the
// SIMD primary pass (hosts/simd/pass.h), then the wavefront of secondary and shadow rays on
// the array bounce by bounce (hosts/wavefront/wavefront.h); the host shades the local term
// from the array's records and sums the ray tree.
#include <fmt/format.h>

#include <string>

#include "fixed/check.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/methods/methods.h"
#include "hosts/methods/phases.h"
#include "hosts/simd/pass.h"
#include "hosts/wavefront/wavefront.h"

namespace zephyr {

namespace {

// --compact none keeps every second child a layer block on: the layout may double at every
// level (wavefront::UncompactedLayoutBytes). Refused before the primary pass when that worst
// case exceeds the memory this process may still allocate, naming the deepest --depth that
// fits and the compaction that needs none of it.
void CheckLayoutFits(const Scene& scene, const RenderOptions& options) {
  const Camera& c = scene.camera;
  const int64_t pixels = int64_t(c.width) * c.height;
  const int pes = simd::MachineProfileOf(options.simd).physicalPes;
  const auto bytes = [&](int depth) {
    return wavefront::UncompactedLayoutBytes(scene, depth, pixels, pes,
                                             options.wavefront.compaction);
  };
  const int depth = options.trace.depth;
  const MemoryLimit limit = AvailableMemory();
  if (bytes(depth) <= limit.bytes) return;
  int fits = depth - 1;
  while (fits > 1 && bytes(fits) > limit.bytes) --fits;
  throw UserError(fmt::format(
      "--compact none at --depth {} needs up to {:.2f} GiB for the bounces' ray layout (a "
      "surface that reflects and transmits may double the layers at every level: {} pixels "
      "over {} PEs, times 2^{}; docs/wavefront.md, \"Compaction\"), more than the {:.2f} GiB "
      "this process may have ({}); give --compact local (it holds the live rays only){}",
      depth, double(bytes(depth)) / double(1ull << 30), pixels, pes, depth - 1,
      double(limit.bytes) / double(1ull << 30), limit.source,
      fits >= 1 && bytes(fits) <= limit.bytes
          ? fmt::format(", or --depth {} or less", fits)
          : std::string()));
}

}  // namespace

void RenderArray(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  const auto tracer = Tracer::Create(scene, options.trace);  // its option errors before the pass
  // The plan, then whether the bounces fit the machine, before the pass's array time.
  simd::PrimaryPlan plan;
  {
    PhaseTimer timer(out.phases, "primaryPass");
    plan = simd::PlanPrimaryPass(scene, options.simd);
  }
  wavefront::CheckBeforePrimaryPass(scene, plan, options.wavefront, options.trace.depth,
                                    simd::MachineProfileOf(options.simd));
  CheckLayoutFits(scene, options);
  simd::PrimaryPass pass = RunTimedPrimaryPass(scene, options, out, std::move(plan));
  TraceStats stats = tracer->BuildWork();
  out.image = Image(c.width, c.height);
  wavefront::WavefrontResult wave;
  {
    PhaseTimer timer(out.phases, "wavefront");
    wave = wavefront::RenderWavefront(*tracer, pass, options.wavefront, out.image.pixels, stats);
  }
  KeepPrimaryPass(std::move(pass), stats, options, out);
  out.wavefront = std::move(wave);
}

}  // namespace zephyr
