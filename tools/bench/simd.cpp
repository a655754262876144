// bench_simd — the whole SIMD primary pass (plan, every array pass, matrix readout, decode and
// the host recompute of uncertain pixels: simd::RunPrimaryPass, as `zephyr render --method
// simd` runs it) on random spheres (`zephyr gen spheres --seed 1`), with 1 host thread and
// with every core: modelled cycles and seconds, host wall seconds, real-time factor (modelled
// / host wall) and the speed-up of every core over one. Medians of 3 runs (1 run at
// 4096x4096). docs/simd.md, "Figures".
//
// The machine may be shared: the load average is printed before and after, and `cpu_s_1`
// (the process's CPU seconds of the 1-thread run) gives `rtf_cpu_1`, the 1-thread factor a
// quiet machine would show; the wall factors are only comparable within one run.
//
//   bench_simd             384x384, 1024x1024, 1920x1080 (16, 64, 256 spheres); 4096x4096 (16)
//   bench_simd --quick     384x384 only
//   ZEPHYR_BENCH_LARGE=1   also 4096x4096 with 64 and 256 spheres (tens of minutes on a busy
//                          2-core machine)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "bitserial/blocks.h"
#include "hosts/scene/gen.h"
#include "hosts/simd/pass.h"

namespace {

using namespace zephyr;

struct Size {
  int width, height;
  std::vector<int> spheres;
  int runs;
};

struct Timing {
  double wall = 0, cpu = 0;  // medians, seconds
};

double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one.empty() ? std::string("unknown") : one + " " + five + " " + fifteen;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Medians of `runs` runs of the whole pass, and the last pass.
Timing Time(const Scene& scene, int threads, int runs, simd::PrimaryPass& pass) {
  std::vector<double> wall, cpu;
  for (int r = 0; r < runs; ++r) {
    simd::SimdOptions o;
    o.threads = threads;
    const double c0 = CpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    pass = simd::RunPrimaryPass(scene, o);
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    cpu.push_back(CpuSeconds() - c0);
  }
  return {Median(wall), Median(cpu)};
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  if (argc > 2 || (argc == 2 && !quick)) {
    std::fprintf(stderr,
                 "usage: bench_simd [--quick]  (ZEPHYR_BENCH_LARGE=1 adds 4096x4096 with "
                 "64 and 256 spheres)\n");
    return 2;
  }
  const char* largeEnv = std::getenv("ZEPHYR_BENCH_LARGE");
  const bool large = largeEnv && std::strcmp(largeEnv, "0") != 0 && *largeEnv;
  std::vector<Size> sizes = {{384, 384, {16, 64, 256}, 3}};
  if (!quick) {
    sizes.push_back({1024, 1024, {16, 64, 256}, 3});
    sizes.push_back({1920, 1080, {16, 64, 256}, 3});
    sizes.push_back({4096, 4096, large ? std::vector<int>{16, 64, 256} : std::vector<int>{16}, 1});
  }
  const int all = bitserial::HardwareThreads();
  std::printf(
      "whole SIMD primary pass (uncertain pixels recomputed), random spheres seed 1;\n"
      "%d host threads = every core; load average before: %s\n",
      all, LoadAverage().c_str());
  std::printf("%10s %7s %6s %6s %12s %10s %9s %9s %10s %8s %8s %9s %6s %9s\n", "size", "spheres",
              "passes", "layers", "cycles", "modelled_s", "host_s_1", "cpu_s_1", "host_s_all",
              "rtf_1", "rtf_all", "rtf_cpu_1", "ratio", "recomputed");
  for (const Size& size : sizes)
    for (int count : size.spheres) {
      const Scene scene = GenerateRandomSpheres(
          {.count = count, .seed = 1, .width = size.width, .height = size.height});
      simd::PrimaryPass one, many;
      const Timing t1 = Time(scene, 1, size.runs, one);
      const Timing tAll = Time(scene, all, size.runs, many);
      const double modelled = one.array.ModelledSeconds();
      std::printf(
          "%5dx%-4d %7d %6d %6d %12.4g %10.3f %9.3f %9.3f %10.3f %8.2f %8.2f %9.2f %6.2f %9lld\n",
          size.width, size.height, count, one.plan.passes, one.plan.layers,
          one.array.cycles.TotalCycles(), modelled, t1.wall, t1.cpu, tAll.wall, modelled / t1.wall,
          modelled / tAll.wall, modelled / t1.cpu, t1.wall / tAll.wall,
          (long long)one.recomputedPixels);
      std::fflush(stdout);
    }
  std::printf("load average after: %s\n", LoadAverage().c_str());
  if (!quick && !large)
    std::printf("not run: 4096x4096 with 64 and 256 spheres (set ZEPHYR_BENCH_LARGE=1)\n");
}
