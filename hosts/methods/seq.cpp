// hosts/methods/seq.cpp — the sequential method (paper §2): the host traces every ray,
// primary and secondary, testing every object.
#include "hosts/methods/methods.h"
#include "hosts/methods/phases.h"

namespace zephyr {

void RenderSeq(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  const auto tracer = Tracer::Create(scene, options.trace);
  TraceStats stats = tracer->BuildWork();
  std::vector<PrimaryHit> hits;
  Progress progress("seq", uint64_t(c.height), options.progress);
  out.image = Image(c.width, c.height);
  RenderRegion(*tracer, 0, 0, c.width, c.height, out.image.pixels, stats,
               options.dumpPrimary.empty() ? nullptr : &hits, [&] { progress.Advance(); });
  progress.Finish();
  out.primary.clear();
  for (const PrimaryHit& h : hits) out.primary.push_back({h, 0});
  out.hostWork = stats;
}

}  // namespace zephyr
