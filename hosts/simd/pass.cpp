// hosts/simd/pass.cpp — the SIMD/sequential method's primary pass: the array program
// (hosts/simd/program.h) run in its array passes, the matrix decoded on the host, uncertain
// pixels, the refine pass, and host shading (docs/simd.md). Every format, bound and object
// program comes from the plan (hosts/simd/plan.h).
#include "hosts/simd/pass.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bitserial/blocks.h"
#include "fixed/check.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/program.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Space;

namespace {

// One run of the program on the array (every array pass): the matrix as read, the passes'
// reports.
struct ArrayRun {
  explicit ArrayRun(int64_t pes) : raw(pes) {}
  MatrixRaw raw;
  ArrayRunReport report;
};

// One array pass's report: its blocked run's cycles and memory, its wall time, its PEs.
ArrayPassReport ReportPass(const bitserial::BlockedRun& run, double hostSeconds, int64_t firstPe,
                           int64_t pes) {
  const bitserial::PeMemory& mem = run.memory;
  return {.cycles = run.report,
          .internalPeakBits = mem.PeakUsed(Space::kInternal),
          .internalCapacityBits = mem.Capacity(Space::kInternal),
          .externalPeakBits = mem.PeakUsed(Space::kExternal),
          .externalCapacityBits = mem.Capacity(Space::kExternal),
          .hostSeconds = hostSeconds,
          .firstPe = firstPe,
          .pes = pes};
}

// One pass's table: its cycle report, its memory, its modelled and host time.
std::string PassTable(const ArrayPassReport& pass) {
  const double modelled = pass.cycles.ModelledSeconds();
  return pass.cycles.Table() +
         fmt::format(
             "memory per virtual PE: internal {} of {} bits, external {} of {} bits\n"
             "modelled time {:.4f} s at {:g} MHz; host time {:.4f} s; real-time factor {:.2f}\n",
             pass.internalPeakBits, pass.internalCapacityBits, pass.externalPeakBits,
             pass.externalCapacityBits, modelled, pass.cycles.Profile().clockHz / 1e6,
             pass.hostSeconds, modelled / pass.hostSeconds);
}

}  // namespace

std::string ArrayRunReport::Table() const {
  if (passes.size() == 1) return PassTable(passes[0]);
  std::string table;
  for (size_t k = 0; k < passes.size(); ++k) {
    const ArrayPassReport& p = passes[k];
    const std::string what =
        rowWidth > 0 ? fmt::format("rows {}..{} ({} virtual PEs)", p.firstPe / rowWidth,
                                   (p.firstPe + p.pes) / rowWidth - 1, p.pes)
                     : fmt::format("virtual PEs {}..{}", p.firstPe, p.firstPe + p.pes - 1);
    table += fmt::format("array pass {} of {}: {}\n", k + 1, passes.size(), what) + PassTable(p);
  }
  const double modelled = ModelledSeconds();
  table += fmt::format(
      "total over {} array passes: {} layers, {:.0f} cycles; modelled time {:.4f} s at {:g} MHz; "
      "host time {:.4f} s; "
      "real-time factor {:.2f}\n",
      passes.size(), cycles.Layers(), cycles.TotalCycles(), modelled,
      cycles.Profile().clockHz / 1e6, hostSeconds, modelled / hostSeconds);
  return table;
}

namespace {

// The host side: decode the matrix, count the flags.
void DecodeMatrix(PrimaryPass& pass, const MatrixRaw& raw) {
  const PrimaryPlan& plan = pass.plan;
  PrimaryMatrix& out = pass.matrix;
  out.width = plan.width, out.height = plan.height;
  out.hits.resize(plan.virtualPes);
  out.flags.assign(plan.virtualPes, 0);
  for (int64_t pe = 0; pe < plan.virtualPes; ++pe) {
    PrimaryHit& h = out.hits[pe];
    h.direction = DecodeDirection(raw.d[0][pe], raw.d[1][pe], raw.d[2][pe], plan.dirFracBits);
    h.object = int(raw.object[pe]) - 1;
    h.t = h.object >= 0 ? std::ldexp(double(raw.t[pe]), -plan.fracBits) : 0.0;
    uint32_t& fl = out.flags[pe];
    if (raw.overflow[pe]) fl |= kOverflow;
    if (raw.grazing[pe]) fl |= kGrazing;
    if (raw.nearTie[pe]) fl |= kNearTie;
    if (fl & kOverflow) ++pass.uncertain.overflow;
    if (fl & kGrazing) ++pass.uncertain.grazing;
    if (fl & kNearTie) ++pass.uncertain.nearTie;
  }
}

// Uncertain pixels by the policy: fail with the counts, keep, or recompute in double.
void HandleUncertain(PrimaryPass& pass, const Scene& scene, const PrimaryRays& rays,
                     UncertainPolicy policy, Accel accel, int threads) {
  PrimaryMatrix& out = pass.matrix;
  const auto isUncertain = [](uint32_t f) { return (f & kUncertainFlags) != 0; };
  const int64_t uncertain = std::count_if(out.flags.begin(), out.flags.end(), isUncertain);
  if (policy == UncertainPolicy::kFail && uncertain > 0)
    throw UserError(fmt::format(
        "the uncertain-pixel policy is fail, and the pass has {} uncertain pixel(s): {} overflow, "
        "{} grazing, {} near tie",
        uncertain, pass.uncertain.overflow, pass.uncertain.grazing, pass.uncertain.nearTie));
  if (policy == UncertainPolicy::kKeep || policy == UncertainPolicy::kFail || uncertain == 0)
    return;
  TraceOptions trace;
  trace.depth = 1;
  trace.accel = accel;
  const auto tracer = Tracer::Create(scene, trace);
  std::vector<int64_t> flagged;
  flagged.reserve(uncertain);
  for (int64_t pe = 0; pe < int64_t(out.flags.size()); ++pe)
    if (isUncertain(out.flags[pe])) flagged.push_back(pe);
  // Each pixel on its own (the tracer is read-only): the same hits whatever the thread count,
  // and the same counts (sums of whole numbers).
  const int64_t n = int64_t(flagged.size());
  TraceStats work = tracer->BuildWork();
#pragma omp parallel num_threads(threads)
  {
    TraceStats stats;
#pragma omp for schedule(dynamic, 64)
    for (int64_t i = 0; i < n; ++i) {
      const int64_t pe = flagged[i];
      out.hits[pe] = tracer->FirstHit(rays.At(int(pe % out.width), int(pe / out.width)), stats);
      out.flags[pe] |= kRecomputed;
    }
#pragma omp critical
    work.Add(stats);
  }
  pass.recomputedPixels += n;
  pass.recomputeWork.Add(work);
}

// The program over the plan's PEs (pixel pixels[k] in PE k; every pixel when empty), in the
// plan's array passes one after the other (docs/simd.md, "Several array passes"), each a
// complete pass with its own layers, matrix readout and cycle report. Each pass runs whole
// on one layer block at a time (bitserial/blocks.h): no operation of the program crosses
// layers, so the matrix, the flags and the cycle report are those of op-by-op execution.
ArrayRun RunArray(const PrimaryPlan& plan, const SimdOptions& options, const PrimaryRays& rays,
                  const std::vector<int64_t>& pixels) {
  ArrayRun run(plan.virtualPes);
  const auto start = std::chrono::steady_clock::now();
  const bitserial::MachineProfile profile = MachineProfileOf(options);
  for (int k = 0; k < plan.passes; ++k) {
    const auto passStart = std::chrono::steady_clock::now();
    const int64_t first = int64_t(k) * plan.pesPerPass,
                  pes = std::min(plan.pesPerPass, plan.virtualPes - first);
    const bitserial::BlockedRun blocked = bitserial::RunLayerBlocks(
        profile, pes, {.blockLayers = options.blockLayers, .threads = options.threads},
        [&](Machine& m) { RunProgram(m, plan, rays, pixels, first, &run.raw); });
    run.report.passes.push_back(ReportPass(
        blocked,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - passStart).count(), first,
        pes));
    run.report.cycles.Add(blocked.report);
  }
  run.report.hostSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.report.rowWidth = pixels.empty() ? plan.width : 0;
  return run;
}

// The refine pass (docs/simd.md, "Refine pass"): the uncertain pixels, compacted, once more
// on the array at wider formats. Every refined pixel takes the refine pass's object, t and
// direction (its t is along that direction, quantised at the refine pass's dirFracBits: with
// the first pass's coarser direction beside it, the pair named no point of the surface and a
// t read along the matrix's direction erred up to 26x the refine bound); a pixel it certifies
// is flagged kRefined, which the heterogeneous entries decode.
void Refine(PrimaryPass& pass, const Scene& scene, const SimdOptions& options,
            const PrimaryRays& rays) {
  PrimaryMatrix& out = pass.matrix;
  std::vector<int64_t> pixels;
  for (int64_t pe = 0; pe < int64_t(out.flags.size()); ++pe)
    if (out.flags[pe] & kUncertainFlags) pixels.push_back(pe);
  if (pixels.empty()) return;
  const PrimaryPlan plan =
      PlanRefinePass(scene, options, pass.plan, int64_t(pixels.size()), kRefineExtraBits);
  const ArrayRun run = RunArray(plan, options, rays, pixels);
  int64_t still = 0, overflow = 0, grazing = 0, tie = 0;
  for (size_t k = 0; k < pixels.size(); ++k) {
    uint32_t fl = 0;
    if (run.raw.overflow[k]) fl |= kOverflow, ++overflow;
    if (run.raw.grazing[k]) fl |= kGrazing, ++grazing;
    if (run.raw.nearTie[k]) fl |= kNearTie, ++tie;
    PrimaryHit& h = out.hits[pixels[k]];
    h.object = int(run.raw.object[k]) - 1;
    h.t = h.object >= 0 ? std::ldexp(double(run.raw.t[k]), -plan.fracBits) : 0.0;
    h.direction =
        DecodeDirection(run.raw.d[0][k], run.raw.d[1][k], run.raw.d[2][k], plan.dirFracBits);
    out.flags[pixels[k]] = fl != 0 ? fl : kRefined;
    still += fl != 0;
  }
  pass.refine =
      RefineResult{.pixels = int64_t(pixels.size()),
                   .layers = plan.layers,
                   .fracBits = plan.fracBits,
                   .dirFracBits = plan.dirFracBits,
                   .tErrorBound = plan.tErrorBound,
                   .stillUncertain = still,
                   .uncertain = {.overflow = overflow, .grazing = grazing, .nearTie = tie},
                   .array = run.report};
}

}  // namespace

PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options) {
  return RunPrimaryPass(scene, options, PlanPrimaryPass(scene, options));
}

PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options, PrimaryPlan plan) {
  PrimaryPass pass;
  pass.plan = std::move(plan);
  const PrimaryRays rays(scene.camera);
  ArrayRun run = RunArray(pass.plan, options, rays, {});
  pass.array = std::move(run.report);
  const auto hostStart = std::chrono::steady_clock::now();
  DecodeMatrix(pass, run.raw);
  run.raw = MatrixRaw(0);  // the decoded matrix holds it all now; free it before the recompute
  const int64_t flagged = std::count_if(pass.matrix.flags.begin(), pass.matrix.flags.end(),
                                        [](uint32_t f) { return (f & kUncertainFlags) != 0; });
  const int64_t budget = int64_t(kAutoRefineShare * double(pass.matrix.flags.size()));
  if (options.uncertain == UncertainPolicy::kRefine ||
      (options.uncertain == UncertainPolicy::kAuto && flagged > budget))
    Refine(pass, scene, options, rays);
  HandleUncertain(pass, scene, rays, options.uncertain, options.hostAccel,
                  options.threads > 0 ? options.threads : bitserial::HardwareThreads());
  pass.recomputeSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - hostStart).count();
  return pass;
}

void ShadeRegion(const Tracer& tracer, const PrimaryMatrix& matrix, int x0, int y0, int w, int h,
                 std::vector<Vec3>& out, TraceStats& stats) {
  ShadeFromHits(tracer, matrix.hits, matrix.width, matrix.height, x0, y0, w, h, out, stats);
}

}  // namespace zephyr::simd
