// bench_simd — the SIMD primary pass at 384×384 (the paper's size) for 16, 64 and 256 random
// spheres: host time of the emulation, modelled cycles and time, real-time factor
// (modelled / host; target >= 10 on one core). Medians of 3 runs.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "hosts/simd/pass.h"
#include "hosts/scene/gen.h"

int main() {
  using namespace zephyr;
  std::printf("%8s %12s %14s %12s %10s %10s\n", "spheres", "host_s", "cycles", "modelled_s", "rtf", "uncertain");
  for (int count : {16, 64, 256}) {
    const Scene scene = GenerateRandomSpheres({.count = count, .seed = 1, .width = 384, .height = 384});
    std::vector<double> host;
    simd::PrimaryPass pass;
    for (int run = 0; run < 3; ++run) {
      simd::SimdOptions o;
      o.uncertain = simd::UncertainPolicy::kKeep;
      pass = simd::RunPrimaryPass(scene, o);
      host.push_back(pass.hostSeconds);
    }
    std::sort(host.begin(), host.end());
    const double median = host[1];
    std::printf("%8d %12.3f %14.4g %12.3f %10.2f %10lld\n", count, median,
                pass.cycles["totalCycles"].get<double>(), pass.modelledSeconds,
                pass.modelledSeconds / median,
                (long long)(pass.overflowPixels + pass.grazingPixels + pass.tiePixels));
  }
}
