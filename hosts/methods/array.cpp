// hosts/methods/array.cpp — every ray on the array (the fifth method; docs/wavefront.md): the
// SIMD primary pass (hosts/simd/pass.h), then the wavefront of secondary and shadow rays on
// the array bounce by bounce (hosts/wavefront/wavefront.h); the host shades the local term
// from the array's records and sums the ray tree.
#include <cstdio>

#include "hosts/methods/methods.h"
#include "hosts/methods/phases.h"
#include "hosts/simd/pass.h"
#include "hosts/wavefront/wavefront.h"

namespace zephyr {

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
  simd::PrimaryPass pass = RunTimedPrimaryPass(scene, options, out, std::move(plan));
  TraceStats stats = tracer->BuildWork();
  out.image = Image(c.width, c.height);
  wavefront::WavefrontResult wave;
  {
    PhaseTimer timer(out.phases, "wavefront");
    wave = wavefront::RenderWavefront(*tracer, pass, options.wavefront, out.image.pixels, stats);
  }
  std::fprintf(stdout,
               "wavefront (compaction %s; s%d.%d, t error <= %.3g, rays ignore hits within %.3g):\n"
               "  bounce      rays      hits  layers passes  utilisation  uncertain rays/shadows  "
               "cycles\n",
               std::string(wavefront::kCompactionNames.NameOf(wave.compaction)).c_str(),
               wave.intBits, wave.fracBits, wave.tErrorBound, wave.epsilon);
  for (const wavefront::BounceReport& b : wave.bounces)
    std::fprintf(stdout, "  %6d %9lld %9lld %7lld %6d %11.1f%% %12lld / %-9lld %.4g\n", b.bounce,
                 (long long)b.rays, (long long)b.hits, (long long)b.layers, b.passes,
                 100 * b.utilisation, (long long)b.uncertainRays, (long long)b.uncertainShadows,
                 b.cycles.TotalCycles());
  std::fprintf(stdout, "  total: %.4g cycles = %.4g s at %.3g Hz (primary pass %.4g s)\n",
               wave.cycles.TotalCycles(), wave.cycles.ModelledSeconds(),
               wave.cycles.Profile().clockHz, pass.array.ModelledSeconds());
  KeepPrimaryPass(std::move(pass), stats, options, out);
  out.wavefront = std::move(wave);
}

}  // namespace zephyr
