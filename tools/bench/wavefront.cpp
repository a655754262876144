// bench_wavefront — every ray on the array (`zephyr render --method array`, docs/wavefront.md)
// on random spheres (`zephyr gen spheres --seed 1`, 384x384, depth 5) and the showcase
// (`zephyr gen showcase`: an ellipsoid, two cones, a cube): per compaction policy the
// primary pass and the wavefront, each with its modelled seconds, host wall seconds and
// real-time factor (modelled / host wall), and their ratio (target: the whole render's factor
// at least half the primary pass's: the bounces may not cost the array more of its speed than
// the primary pass does); the image's PSNR against the sequential
// tracer's; per bounce the rays, layers, utilisation and the share the host traced; and the
// exact check of the certain secondary rays (every one at 64 spheres, every 4th at 256; wrong
// certain hits: target 0). Medians of 3.
//
//   bench_wavefront              64 and 256 spheres (mesh and local; none at 64), the showcase
//   bench_wavefront --quick      64 spheres, mesh only
//   bench_wavefront --showcase   the showcase only (one run)
#include "hosts/wavefront/wavefront.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hosts/scene/gen.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/image.h"

namespace {

using namespace zephyr;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

Scene Spheres(int count) {
  return GenerateRandomSpheres({.count = count, .seed = 1, .width = 384, .height = 384});
}

void Run(const Scene& scene, const char* name, wavefront::Compaction compaction, int runs) {
  const auto tracer = Tracer::Create(scene, {});
  Image seq(384, 384), array(384, 384);
  TraceStats seqStats;
  RenderRegion(*tracer, 0, 0, 384, 384, seq.pixels, seqStats);
  std::vector<double> primaryWall, waveWall;
  simd::PrimaryPass pass;
  wavefront::WavefrontResult wave;
  wavefront::WavefrontOptions options;
  options.compaction = compaction;
  for (int r = 0; r < runs; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    pass = simd::RunPrimaryPass(scene, {});
    primaryWall.push_back(Seconds(t0));
    TraceStats host;
    t0 = std::chrono::steady_clock::now();
    wave = wavefront::RenderWavefront(*tracer, pass, options, array.pixels, host);
    waveWall.push_back(Seconds(t0));
  }
  const double pm = pass.array.ModelledSeconds(), wm = wave.cycles.ModelledSeconds();
  const double pw = Median(primaryWall), ww = Median(waveWall);
  const double primaryRtf = pm / pw, wholeRtf = (pm + wm) / (pw + ww);
  std::printf(
      "%-11s --compact %-5s  primary pass %.3g s modelled in %.3g s (rtf %.1f); "
      "wavefront %.3g s in %.3g s; whole render rtf %.1f = %.2f x the pass's (target >= 0.5); "
      "PSNR vs seq %.2f dB\n",
      name, wavefront::kCompactionNames.NameOf(compaction), pm, pw, primaryRtf, wm, ww, wholeRtf,
      wholeRtf / primaryRtf, Psnr(array, seq));
  for (const wavefront::BounceReport& b : wave.bounces)
    std::printf(
        "    bounce %d: %7lld rays %4lld layers utilisation %5.1f%%  host traced %.2f%% of "
        "the rays, %.2f%% of the shadow rays\n",
        b.bounce, (long long)b.rays, (long long)b.layers, 100 * b.utilisation,
        b.rays ? 100.0 * b.uncertainRays / b.rays : 0.0,
        b.hits ? 100.0 * b.uncertainShadows / (b.hits * scene.lights.size()) : 0.0);
}

// Every `stride`-th certain secondary ray against the exact first hit along it (AuditRay's rules).
void ExactCheck(const Scene& scene, const char* name, int stride) {
  const auto tracer = Tracer::Create(scene, {});
  const simd::PrimaryPass pass = simd::RunPrimaryPass(scene, {});
  int64_t seen = 0, checked = 0, wrong = 0;
  wavefront::WavefrontOptions options;
  options.audit = [&](const wavefront::AuditRay& a) {
    if (a.uncertain || seen++ % stride != 0) return;
    ++checked;
    wrong += wavefront::ExactFirstObject(scene, a) != a.object;
  };
  std::vector<Vec3> pixels;
  TraceStats host;
  wavefront::RenderWavefront(*tracer, pass, options, pixels, host);
  std::printf(
      "%-11s %lld of %lld certain secondary rays checked exactly, %lld wrong "
      "(target 0)\n",
      name, (long long)checked, (long long)seen, (long long)wrong);
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const bool showcase = argc > 1 && std::strcmp(argv[1], "--showcase") == 0;
  using wavefront::Compaction;
  const Scene s64 = Spheres(64), s256 = Spheres(256);
  // The showcase: an ellipsoid, a sheared cylinder, a transformed cone and a cube on a floor.
  const Scene show = GenerateTransformedShowcase(384, 384);
  if (quick) {
    Run(s64, "64 spheres", Compaction::kMesh, 1);
    ExactCheck(s64, "64 spheres", 1);
    return 0;
  }
  if (!showcase) {
    Run(s64, "64 spheres", Compaction::kMesh, 3);
    Run(s64, "64 spheres", Compaction::kLocal, 3);
    Run(s256, "256 spheres", Compaction::kMesh, 3);
    Run(s256, "256 spheres", Compaction::kLocal, 3);
    Run(s64, "64 spheres", Compaction::kNone, 1);
  }
  Run(show, "showcase", Compaction::kMesh, showcase ? 1 : 3);
  if (!showcase) {
    ExactCheck(s64, "64 spheres", 1);
    ExactCheck(s256, "256 spheres", 4);
  }
  ExactCheck(show, "showcase", 1);
  return 0;
}
