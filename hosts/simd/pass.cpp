// hosts/simd/pass.cpp — the SIMD/sequential method's primary pass on the array, the matrix
// on the host, uncertain pixels, and host shading (docs/simd.md). Every format, bound and
// object program comes from the plan (hosts/simd/plan.h).
#include "hosts/simd/pass.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bitserial/blocks.h"
#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Space;
using fixed::Fixed;
using fixed::Format;

nlohmann::json PrimaryPass::Json() const {
  nlohmann::json j = {{"plan", plan.Json()},
          {"cycles", cycles},
          {"hostSeconds", hostSeconds},
          {"modelledSeconds", modelledSeconds},
          {"realTimeFactor", hostSeconds > 0 ? modelledSeconds / hostSeconds : 0.0},
          {"recomputeSeconds", recomputeSeconds},
          {"uncertain", {{"overflow", overflowPixels}, {"grazing", grazingPixels},
                         {"nearTie", tiePixels}, {"recomputed", recomputedPixels}}}};
  if (!refine.is_null()) j["refine"] = refine;
  return j;
}

namespace {

// The per-pixel matrix on the array, in external memory in this order (docs/simd.md, "The
// matrix layout").
struct ArrayMatrix {
  ArrayMatrix(Machine& m, const PrimaryPlan& plan)
      : object(m, plan.object, "matrix.object", Space::External),
        t(m, plan.t, "matrix.t", Space::External),
        d{Multi(m, plan.direction, "matrix.dx", Space::External), Multi(m, plan.direction, "matrix.dy", Space::External),
          Multi(m, plan.direction, "matrix.dz", Space::External)},
        grazing(m, bitserial::BoolFormat(), "matrix.grazing", Space::External),
        nearTie(m, bitserial::BoolFormat(), "matrix.nearTie", Space::External) {}
  Multi object, t, d[3], grazing, nearTie;
};

// The host computes each pixel's eye ray and loads the directions (one plane per bit) into
// the machine's PEs (a layer block's own, from m.FirstPe()): PE k takes pixel pixels[k], or
// pixel k when `pixels` is empty (row-major).
void LoadDirections(Machine& m, ArrayMatrix& a, const PrimaryRays& rays, const PrimaryPlan& plan,
                    const std::vector<int64_t>& pixels) {
  std::vector<int64_t> raw[3];
  for (auto& r : raw) r.resize(m.VirtualPes());
  for (int64_t i = 0; i < m.VirtualPes(); ++i) {
    const int64_t pe = m.FirstPe() + i, pixel = pixels.empty() ? pe : pixels[pe];
    const Vec3 dir = rays.At(int(pixel % plan.width), int(pixel / plan.width)).direction;
    for (int k = 0; k < 3; ++k) raw[k][i] = QuantiseDirection(dir[k], plan.dirFracBits);
  }
  for (int k = 0; k < 3; ++k) a.d[k].LoadRaw(raw[k]);
}

// Near ties per pair (docs/simd.md, "Uncertain pixels"): the final best k and another hit j
// are tied when t_j − e_j <= t_k + e_k. Each PE keeps lowBest = t − e of its current best
// and otherLow, the least t − e of every other hit so far; a displaced best's low joins
// otherLow. bestUnsure: the current best was itself uncertain (its e does not hold);
// tGraze: the least tLow of an uncertain candidate. bestPlane (only when some plane holds
// several polygons): the plane class of the current best (ObjectPlan::planeClass, 0: none).
struct Trackers {
  Trackers(Machine& m, const Fixed& tMax, const PrimaryPlan& plan)
      : tGraze(Broadcast(m, tMax)), otherLow(Broadcast(m, tMax)), lowBest(Broadcast(m, tMax)),
        bestUnsure(Broadcast(m, Fixed{bitserial::BoolFormat(), 0})) {
    if (plan.planeClasses > 0) bestPlane = Broadcast(m, Fixed{PlaneFormat(plan), 0});
  }
  static Format PlaneFormat(const PrimaryPlan& plan) {
    return Format::Unsigned(std::max(1, CeilLog2(double(plan.planeClasses) + 1)), 0);
  }
  Multi tGraze, otherLow, lowBest, bestUnsure, bestPlane;
};

// One object's candidate folded into the best hit so far and the trackers.
void FoldCandidate(Machine& m, const ObjectPlan& object, const PrimaryPlan& plan, ArrayMatrix& a, Trackers& k) {
  const Format T = plan.t;
  const Candidate c = object.program->Run(m, a.d);
  // t − e_i with e_i rounded up (an always-uncertain object's every hit is flagged, so its
  // e is never relied on); saturating down only widens the test.
  const double e = object.bounds.alwaysUncertain ? 0.0 : object.bounds.tError + plan.pass.Ulp();
  Multi low;
  WithExpectedSaturation(m, [&] { low = Sub(c.t, Broadcast(m, Tight(e, plan.fracBits)), T, kSaturate); });
  Where(c.uncertain, [&] { k.tGraze = Min(k.tGraze, c.tLow, T); });
  const Multi closer = c.hit && (c.t < a.t);
  // A polygon in the best's plane has the best's t bit for bit and ties with it exactly: the
  // lower index (the best) stays first, as in the exact reference, and it is no near tie.
  Multi other = c.hit && !closer;
  if (object.planeClass > 0)
    other = other && !Equal(k.bestPlane, bitserial::Uni{Fixed{k.bestPlane.Format(), fixed::BigInt(object.planeClass)}});
  Where(other, [&] { k.otherLow = Min(k.otherLow, low, T); });
  Where(closer, [&] {
    if (!k.bestPlane.Empty())
      k.bestPlane = Broadcast(m, Fixed{k.bestPlane.Format(), fixed::BigInt(object.planeClass)});
    k.otherLow = Min(k.otherLow, k.lowBest, T);
    k.lowBest = low;
    k.bestUnsure = c.uncertain;
    a.t = c.t;
    a.object = Broadcast(m, Fixed{plan.object, fixed::BigInt(object.index + 1)});
  });
}

// A flagged candidate or another hit matters only if it may lie in front of the final best's
// true t <= tBest + e_best (= 2·tBest − lowBest; tMax marks "none"; the limit's exact format
// cannot overflow). An uncertain best is grazing itself.
void SetFlags(Machine& m, const Fixed& tMax, ArrayMatrix& a, const Trackers& k) {
  const Multi limit = a.t + (a.t - k.lowBest), none = Broadcast(m, tMax);
  a.grazing = k.bestUnsure || ((k.tGraze <= limit) && (k.tGraze < none));
  a.nearTie = (k.otherLow <= limit) && (k.otherLow < none);
}

// The matrix as the host reads it (charged to the host link), and the per-PE flags, over
// every PE of the pass (each layer block writes its own PEs).
struct MatrixRaw {
  explicit MatrixRaw(int64_t pes)
      : object(pes), t(pes), d{std::vector<int64_t>(pes), std::vector<int64_t>(pes), std::vector<int64_t>(pes)},
        grazing(pes), nearTie(pes), overflow(pes) {}
  std::vector<int64_t> object, t, d[3], grazing, nearTie;
  std::vector<uint8_t> overflow;  // overflow or divide by zero (Invalid: √ of a miss)
};

void ReadMatrix(Machine& m, const ArrayMatrix& a, MatrixRaw& r) {
  const int64_t first = m.FirstPe();
  auto read = [first](const Multi& x, std::vector<int64_t>& to) {
    const std::vector<int64_t> raw = x.ReadRaw();
    std::copy(raw.begin(), raw.end(), to.begin() + first);
  };
  read(a.object, r.object), read(a.t, r.t);
  for (int k = 0; k < 3; ++k) read(a.d[k], r.d[k]);
  read(a.grazing, r.grazing), read(a.nearTie, r.nearTie);
  m.Charge("hostRead", bitserial::HostTransferCost(1));  // the overflow flags
  for (int64_t pe = 0; pe < m.VirtualPes(); ++pe) r.overflow[first + pe] = m.Overflow(pe) || m.DivideByZero(pe);
}

// One run of the program on the array: the matrix as read, the cycle report and timing.
struct ArrayRun {
  explicit ArrayRun(int64_t pes) : raw(pes) {}
  MatrixRaw raw;
  nlohmann::json cycles;
  std::string cycleTable;
  double hostSeconds = 0, modelledSeconds = 0;
};

// The cycle report, memory and timing of the array part.
void ReportCycles(ArrayRun& pass, const bitserial::BlockedRun& run, const bitserial::MachineProfile& profile) {
  const bitserial::CycleReport& report = run.report;
  pass.modelledSeconds = report.ModelledSeconds();
  pass.cycles = report.Json();
  const bitserial::PeMemory& mem = run.memory;
  pass.cycles["memory"] = {
      {"internal", {{"peakBitsPerPe", mem.PeakUsed(Space::Internal)}, {"capacityBitsPerPe", mem.Capacity(Space::Internal)}}},
      {"external", {{"peakBitsPerPe", mem.PeakUsed(Space::External)}, {"capacityBitsPerPe", mem.Capacity(Space::External)}}}};
  pass.cycles["hostSeconds"] = pass.hostSeconds;
  pass.cycles["realTimeFactor"] = pass.modelledSeconds / pass.hostSeconds;
  pass.cycleTable = report.Table() +
                    fmt::format("memory per virtual PE: internal {} of {} bits, external {} of {} bits\n"
                                "modelled time {:.4f} s at {:g} MHz; host time {:.4f} s; real-time factor {:.2f}\n",
                                mem.PeakUsed(Space::Internal), mem.Capacity(Space::Internal),
                                mem.PeakUsed(Space::External), mem.Capacity(Space::External),
                                pass.modelledSeconds, profile.clockHz / 1e6, pass.hostSeconds,
                                pass.modelledSeconds / pass.hostSeconds);
}

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
    if (fl & kOverflow) ++pass.overflowPixels;
    if (fl & kGrazing) ++pass.grazingPixels;
    if (fl & kNearTie) ++pass.tiePixels;
  }
}

// Uncertain pixels by the policy: fail with the counts, keep, or recompute in double.
void HandleUncertain(PrimaryPass& pass, const Scene& scene, const PrimaryRays& rays, UncertainPolicy policy,
                     int threads) {
  PrimaryMatrix& out = pass.matrix;
  const int64_t uncertain = std::count_if(out.flags.begin(), out.flags.end(), [](uint32_t f) { return f != 0; });
  if (policy == UncertainPolicy::kFail && uncertain > 0)
    throw UserError(fmt::format("--uncertain fail: {} uncertain pixel(s): {} overflow, {} grazing, {} near tie",
                                uncertain, pass.overflowPixels, pass.grazingPixels, pass.tiePixels));
  if ((policy != UncertainPolicy::kRecompute && policy != UncertainPolicy::kRefine) || uncertain == 0) return;
  TraceOptions trace;
  trace.depth = 1;
  const auto tracer = Tracer::Create(scene, trace);
  std::vector<int64_t> flagged;
  flagged.reserve(uncertain);
  for (int64_t pe = 0; pe < int64_t(out.flags.size()); ++pe)
    if (out.flags[pe]) flagged.push_back(pe);
  // Each pixel on its own (the tracer is read-only): the same hits whatever the thread count.
  const int64_t n = int64_t(flagged.size());
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
  for (int64_t i = 0; i < n; ++i) {
    const int64_t pe = flagged[i];
    TraceStats stats;
    out.hits[pe] = tracer->FirstHit(rays.At(int(pe % out.width), int(pe / out.width)), stats);
    out.flags[pe] |= kRecomputed;
  }
  pass.recomputedPixels += n;
}

}  // namespace

namespace {

// The program over the plan's PEs (pixel pixels[k] in PE k; every pixel when empty), run
// whole on each layer block in turn (bitserial/blocks.h): no operation of the pass crosses
// layers, so the matrix, the flags and the cycle report are those of op-by-op execution.
ArrayRun RunArray(const Scene& scene, const PrimaryPlan& plan, const SimdOptions& options, const PrimaryRays& rays,
                  const std::vector<int64_t>& pixels) {
  ArrayRun run(plan.virtualPes);
  const auto start = std::chrono::steady_clock::now();
  const bitserial::MachineProfile profile = MachineProfileOf(options);
  const bitserial::BlockedRun blocked = bitserial::RunLayerBlocks(
      profile, plan.virtualPes, {.blockLayers = options.blockLayers, .threads = options.threads},
      [&](Machine& m) {
        ArrayMatrix matrix(m, plan);
        LoadDirections(m, matrix, rays, plan, pixels);
        const Fixed tMax{plan.t, plan.t.MaxRaw()};
        matrix.t = Broadcast(m, tMax);
        Trackers trackers(m, tMax, plan);
        for (const ObjectPlan& object : plan.objects) FoldCandidate(m, object, plan, matrix, trackers);
        SetFlags(m, tMax, matrix, trackers);
        ReadMatrix(m, matrix, run.raw);
      });
  run.hostSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ReportCycles(run, blocked, profile);
  return run;
}

// The refine pass (docs/simd.md, "Refine pass"): the uncertain pixels, compacted, once more
// on the array at wider formats; a pixel it certifies takes its object and t (the direction
// stays the first pass's, as the matrix and the heterogeneous entries decode it).
void Refine(PrimaryPass& pass, const Scene& scene, const SimdOptions& options, const PrimaryRays& rays) {
  PrimaryMatrix& out = pass.matrix;
  std::vector<int64_t> pixels;
  for (int64_t pe = 0; pe < int64_t(out.flags.size()); ++pe)
    if (out.flags[pe]) pixels.push_back(pe);
  if (pixels.empty()) return;
  const PrimaryPlan plan = PlanRefinePass(scene, options, pass.plan, int64_t(pixels.size()), kRefineExtraBits);
  const ArrayRun run = RunArray(scene, plan, options, rays, pixels);
  int64_t still = 0, overflow = 0, grazing = 0, tie = 0;
  for (size_t k = 0; k < pixels.size(); ++k) {
    uint32_t fl = 0;
    if (run.raw.overflow[k]) fl |= kOverflow, ++overflow;
    if (run.raw.grazing[k]) fl |= kGrazing, ++grazing;
    if (run.raw.nearTie[k]) fl |= kNearTie, ++tie;
    PrimaryHit& h = out.hits[pixels[k]];
    h.object = int(run.raw.object[k]) - 1;
    h.t = h.object >= 0 ? std::ldexp(double(run.raw.t[k]), -plan.fracBits) : 0.0;
    out.flags[pixels[k]] = fl;
    still += fl != 0;
  }
  pass.refinedPixels = int64_t(pixels.size());
  pass.refine = {{"pixels", pixels.size()}, {"layers", plan.layers}, {"fracBits", plan.fracBits},
                 {"dirFracBits", plan.dirFracBits}, {"tErrorBound", plan.tErrorBound},
                 {"stillUncertain", still},
                 {"uncertain", {{"overflow", overflow}, {"grazing", grazing}, {"nearTie", tie}}},
                 {"hostSeconds", run.hostSeconds}, {"modelledSeconds", run.modelledSeconds},
                 {"cycles", run.cycles}};
  pass.refineCycleTable = run.cycleTable;
}

}  // namespace

PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options) {
  PrimaryPass pass;
  pass.plan = PlanPrimaryPass(scene, options);
  const PrimaryRays rays(scene.camera);
  ArrayRun run = RunArray(scene, pass.plan, options, rays, {});
  pass.cycles = std::move(run.cycles);
  pass.cycleTable = std::move(run.cycleTable);
  pass.hostSeconds = run.hostSeconds;
  pass.modelledSeconds = run.modelledSeconds;
  const auto hostStart = std::chrono::steady_clock::now();
  DecodeMatrix(pass, run.raw);
  if (options.uncertain == UncertainPolicy::kRefine) Refine(pass, scene, options, rays);
  HandleUncertain(pass, scene, rays, options.uncertain,
                  options.threads > 0 ? options.threads : bitserial::HardwareThreads());
  pass.recomputeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - hostStart).count();
  return pass;
}

void ShadeRegion(const Tracer& tracer, const PrimaryMatrix& matrix, int x0, int y0, int w, int h,
                 std::vector<Vec3>& out, TraceStats& stats) {
  ZEPHYR_CHECK(x0 >= 0 && y0 >= 0 && w >= 0 && h >= 0 && x0 + w <= matrix.width &&
               y0 + h <= matrix.height);
  out.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      PrimaryHit hit = matrix.hits[size_t(y0 + y) * matrix.width + x0 + x];
      ++stats.rays[int(RayKind::kPrimary)];
      // A fixed-point t is off by up to the plan's bound, enough to put the hit point on
      // the wrong side of the surface so secondary rays re-hit it (docs/simd.md, "Uncertain pixels"). The host
      // refines t against the one object the array found (one double test, not N).
      if (hit.object >= 0) {
        const Scene& scene = tracer.GetScene();
        const double tMin = std::max(scene.camera.hither, 0.0);
        ++stats.tests[int(scene.objects[hit.object].Kind())];
        ++stats.hits;
        if (auto t = IntersectObject(scene, hit.object, scene.camera.from, hit.direction, tMin,
                                     tracer.Options().sphereTest))
          hit.t = *t;
      }
      out[size_t(y) * w + x] = tracer.ShadeFromPrimaryHit(hit, stats);
      ++stats.pixels;
    }
}

}  // namespace zephyr::simd
