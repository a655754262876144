// hosts/methods/simd.cpp — the SIMD/sequential method (paper §3): the primary pass on the
// emulated array (hosts/simd/pass.h), secondary rays shaded on the host from its matrix.
#include "hosts/methods/methods.h"
#include "hosts/methods/phases.h"
#include "hosts/simd/pass.h"

namespace zephyr {

simd::PrimaryPass RunTimedPrimaryPass(const Scene& scene, const RenderOptions& options,
                                      RenderOutput& out, std::optional<simd::PrimaryPlan> plan) {
  simd::PrimaryPass pass;
  {
    PhaseTimer timer(out.phases, "primaryPass");
    pass = plan ? simd::RunPrimaryPass(scene, options.simd, std::move(*plan))
                : simd::RunPrimaryPass(scene, options.simd);
  }
  return pass;
}

void KeepPrimaryPass(simd::PrimaryPass pass, const TraceStats& hostWork,
                     const RenderOptions& options, RenderOutput& out) {
  out.primary.clear();
  if (!options.dumpPrimary.empty())
    for (size_t i = 0; i < pass.matrix.hits.size(); ++i)
      out.primary.push_back({pass.matrix.hits[i], pass.matrix.flags[i]});
  out.hostWork = hostWork;
  pass.matrix = {};  // the image and the dump have it
  out.simd = std::move(pass);
}

void RenderSimd(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  const auto tracer = Tracer::Create(scene, options.trace);  // its option errors before the pass
  simd::PrimaryPass pass = RunTimedPrimaryPass(scene, options, out);
  TraceStats stats = tracer->BuildWork();
  out.image = Image(c.width, c.height);
  {
    PhaseTimer timer(out.phases, "hostShading");
    simd::ShadeRegion(*tracer, pass.matrix, 0, 0, c.width, c.height, out.image.pixels, stats);
  }
  KeepPrimaryPass(std::move(pass), stats, options, out);
}

}  // namespace zephyr
