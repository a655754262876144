// hosts/simd/pass.cpp — the SIMD/sequential method's planner, primary pass and host shading
// (docs/simd.md).
#include "hosts/simd/pass.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/simd/ops.h"
#include "hosts/simd/shapes.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Space;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;

UncertainPolicy ParseUncertainPolicy(const std::string& name) {
  if (name == "recompute") return UncertainPolicy::kRecompute;
  if (name == "keep") return UncertainPolicy::kKeep;
  if (name == "fail") return UncertainPolicy::kFail;
  throw UserError("--uncertain: expected recompute, keep or fail, got '" + name + "'");
}
const char* UncertainPolicyName(UncertainPolicy p) {
  return p == UncertainPolicy::kRecompute ? "recompute" : p == UncertainPolicy::kKeep ? "keep" : "fail";
}

namespace {

int CeilLog2(double x) { return x <= 1 ? 0 : int(std::ceil(std::log2(x))); }

bitserial::MachineProfile MakeProfile(const SimdOptions& o) {
  bitserial::MachineProfile p = bitserial::Profile(o.profile);
  for (const std::string& a : o.profileOverrides) p.Override(a);
  return p;
}

PassFormats FormatsOf(const PrimaryPlan& plan, const Scene& scene) {
  PassFormats pf;
  pf.fracBits = plan.fracBits;
  pf.dirFracBits = plan.dirFracBits;
  pf.t = plan.t;
  pf.hither = std::max(scene.camera.hither, 0.0);
  return pf;
}

// Integer bits for values of magnitude up to `bound` (at least 1).
int IntBitsFor(double bound) { return std::max(1, CeilLog2(bound + 1)); }

}  // namespace

PrimaryPlan PlanPrimaryPass(const Scene& scene, const SimdOptions& options) {
  const bitserial::MachineProfile profile = MakeProfile(options);
  const Camera& cam = scene.camera;
  PrimaryPlan plan;
  plan.width = cam.width, plan.height = cam.height;
  plan.virtualPes = int64_t(cam.width) * cam.height;
  plan.layers = int((plan.virtualPes + profile.physicalPes - 1) / profile.physicalPes);
  // The scene's range: the farthest point of an array object and the smallest feature
  // (a sphere's radius, an ellipsoid's smallest semi-axis, a polygon's shortest edge / 2).
  double farthest = 1, rMin = 1e300, rMax = 1;
  int arrayObjects = 0;
  PassFormats probe;
  probe.fracBits = probe.dirFracBits = 16;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Primitive& p = scene.objects[i];
    farthest = std::max(farthest, BoundObject(scene, int(i), probe).farthest);
    double feature = 1e300;
    if (const Sphere* s = std::get_if<Sphere>(&p.shape)) {
      feature = s->radius;
      if (p.transform) {  // smallest semi-axis r·σ_min(T) >= r / ‖T⁻¹‖_F
        const Affine inv = p.transform->Inverse();
        double norm = 0;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) norm += inv.m[r][c] * inv.m[r][c];
        feature /= std::sqrt(norm);
      }
      rMax = std::max(rMax, s->radius);
    } else if (const Polygon* poly = std::get_if<Polygon>(&p.shape)) {
      for (size_t k = 0; k < poly->vertices.size(); ++k) {
        const Vec3 a = p.transform ? p.transform->ApplyPoint(poly->vertices[k]) : poly->vertices[k];
        const Vec3 b = p.transform ? p.transform->ApplyPoint(poly->vertices[(k + 1) % poly->vertices.size()])
                                   : poly->vertices[(k + 1) % poly->vertices.size()];
        feature = std::min(feature, Length(a - b) / 2);
      }
    } else if (const Cone* cone = std::get_if<Cone>(&p.shape)) {
      // Half the larger radius, or half the height, in world units (r / ‖T⁻¹‖_F).
      feature = std::min(std::max(std::abs(cone->baseRadius), std::abs(cone->apexRadius)),
                         Length(cone->apex - cone->base)) / 2;
      if (p.transform) {
        const Affine inv = p.transform->Inverse();
        double norm = 0;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) norm += inv.m[r][c] * inv.m[r][c];
        feature /= std::sqrt(norm);
      }
    }
    rMin = std::min(rMin, feature);
    ++arrayObjects;
  }
  if (arrayObjects == 0 || !(rMin > 0) || rMin > 1e299) rMin = 1;
  // Distances: t and the eye-to-centre terms reach `farthest`; one more bit for tca ± root.
  plan.distIntBits = options.formats.intBits >= 0 ? options.formats.intBits : IntBitsFor(farthest) + 1;
  // Fraction bits: the t error bound (≈ 60·D·2^-F, docs/simd.md) at most 1/64 of the
  // smallest feature, and never coarser than 2^-10.
  const int planned = std::clamp(CeilLog2(64.0 * 60.0 * farthest / rMin), 10, 40);
  plan.fracBits = options.formats.fracBits >= 0 ? options.formats.fracBits : planned;
  plan.dirFracBits = options.formats.dirFracBits >= 0 ? options.formats.dirFracBits : plan.fracBits;
  if (plan.fracBits > 56 || plan.dirFracBits > 60 || plan.distIntBits > 40)
    throw UserError(fmt::format("formats too wide for the primary pass: {} integer bits, {} fraction "
                                "bits, {} direction fraction bits (limits 40, 56, 60)",
                                plan.distIntBits, plan.fracBits, plan.dirFracBits));
  const int L = plan.distIntBits, F = plan.fracBits, R = IntBitsFor(rMax);
  plan.objectBits = std::max(1, CeilLog2(double(scene.objects.size()) + 1));
  plan.direction = Format::Signed(1, plan.dirFracBits);
  plan.length = Format::Signed(L, F);
  plan.t = Format::Signed(L, F);
  plan.object = Format::Unsigned(plan.objectBits, 0);
  const std::string dist = fmt::format("farthest point of an array object is {:.4g} from the eye", farthest);
  plan.formats = {
      {"direction d (x,y,z)", plan.direction, "unit components in [-1,1]; fraction bits = F"},
      {"eye-to-centre f (uni)", plan.length, dist},
      {"tca = f·d, cross f×d", plan.length, "|f·d|, |f×d| <= |f|"},
      {"cross, clamped", Format::Signed(R, F), fmt::format("only |f×d| <= r = {:.4g} can hit; larger saturate (a miss)", rMax)},
      {"squares, their sum", Format::Unsigned(2 * R + 2, F), "three squares of the clamped cross product"},
      {"discriminant r²−|f×d|²", Format::Signed(2 * R + 2, F), "difference of the above"},
      {"root √disc", Format::Unsigned(R + 1, F), "half the discriminant's integer bits"},
      {"t = tca ∓ root", plan.t, "t <= farthest (one bit of headroom)"},
      {"object index + 1", plan.object, fmt::format("{} objects, 0 = none", scene.objects.size())},
  };
  // Error bounds per object, derived from these formats (docs/simd.md, "Error bounds").
  const PassFormats pf = FormatsOf(plan, scene);
  plan.grazingFraction = 1.0 / 8;
  int ellipsoids = 0, polygons = 0, ellipsoidBits = 0, cones = 0, coneBits = 0;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const ObjectBounds b = BoundObject(scene, int(i), pf);
    if (!b.alwaysUncertain) plan.tErrorBound = std::max(plan.tErrorBound, b.tError);
    else ++plan.alwaysUncertainObjects;
    if (b.kind == ShapeKind::kPolygon) ++polygons;
    if (b.kind == ShapeKind::kSphere && b.transformed) ++ellipsoids, ellipsoidBits = std::max(ellipsoidBits, b.intBits);
    if (b.kind == ShapeKind::kCone) ++cones, coneBits = std::max(coneBits, b.intBits);
  }
  if (ellipsoids)
    plan.formats.push_back({"ellipsoid d' = T⁻¹d, f·d', f×d'", Format::Signed(ellipsoidBits, F),
                            fmt::format("{} transformed sphere(s): |f|·|d'|, |d'| <= Σ|T⁻¹ row|; t = (f·d' ∓ √disc)/|d'|² by division", ellipsoids)});
  if (polygons)
    plan.formats.push_back({"polygon edge/plane ĝ·d, n̂·d", Format::Signed(1, F),
                            fmt::format("{} polygon(s): unit uni normals (T folded in on the host); t = dist/(n̂·d) by division", polygons)});
  if (cones)
    plan.formats.push_back({"cone A, disc, √, t, height", Format::Signed(coneBits, F),
                            fmt::format("{} cone(s)/cylinder(s): linear forms of d (T⁻¹ folded in), squares up to "
                                        "the widest; t = −sgn(β)·Q/A and −sgn(β)·C/Q by division where |divisor| >= "
                                        "its threshold, else flagged unless certainly beyond the cone",
                                        cones)});
  // Memory per virtual PE: the matrix (object, t, d, two flag bits) plus the temporaries
  // of one sphere test (tca, 3 cross, 3 clamped, 3 squares, sum, disc, root, t0, t1, t and
  // the 1-bit masks), the near-tie and grazing trackers.
  plan.matrixBitsPerPe = plan.objectBits + plan.t.Width() + 3 * plan.direction.Width() + 2;
  const int wl = plan.length.Width(), ws = 2 * R + 3 + F;
  plan.memoryBitsPerPe = plan.matrixBitsPerPe + 2 * plan.t.Width() + 6 * wl + 3 * (R + 1 + F) +
                         5 * ws + 4 * plan.t.Width() + 8;
  plan.internalCapacity = profile.internalBitsPerPe / plan.layers;
  plan.externalCapacity = profile.externalBitsPerPe / plan.layers;
  if (plan.memoryBitsPerPe > plan.internalCapacity + plan.externalCapacity)
    throw UserError(fmt::format(
        "the scene does not fit the {} array: the primary pass needs about {} bits per virtual "
        "PE (t {}, direction {}, {} layers for {}x{} pixels) but each virtual PE has {} internal + "
        "{} external bits; use a smaller image or fewer bits (--frac-bits, --int-bits)",
        profile.name, plan.memoryBitsPerPe, plan.t.Name(), plan.direction.Name(), plan.layers,
        cam.width, cam.height, plan.internalCapacity, plan.externalCapacity));
  return plan;
}

nlohmann::json PrimaryPlan::Json() const {
  nlohmann::json j = {{"width", width}, {"height", height}, {"virtualPes", virtualPes},
                      {"layers", layers}, {"distIntBits", distIntBits}, {"fracBits", fracBits},
                      {"dirFracBits", dirFracBits}, {"objectBits", objectBits},
                      {"tErrorBound", tErrorBound},
                      {"grazingFraction", grazingFraction}, {"memoryBitsPerPe", memoryBitsPerPe},
                      {"matrixBitsPerPe", matrixBitsPerPe}, {"internalCapacity", internalCapacity},
                      {"externalCapacity", externalCapacity},
                      {"alwaysUncertainObjects", alwaysUncertainObjects}};
  for (const PlannedFormat& f : formats)
    j["formats"].push_back({{"quantity", f.quantity}, {"format", f.format.Name()}, {"reason", f.reason}});
  return j;
}

std::string PrimaryPlan::Text() const {
  std::string s = fmt::format("{}x{} pixels = {} virtual PEs in {} layer(s)\n", width, height,
                              virtualPes, layers);
  for (const PlannedFormat& f : formats)
    s += fmt::format("  {:<26} {:<8} {}\n", f.quantity, f.format.Name(), f.reason);
  s += fmt::format("error bound on t (certain pixels): {:.3g} (the largest object's e); near tie per pair: "
                   "|t_i - t_j| <= e_i + e_j; grazing when disc < max((r/{:g})^2, 2 x its error "
                   "bound), per object\n",
                   tErrorBound, 1 / grazingFraction);
  s += fmt::format("memory per virtual PE: ~{} bits (matrix {} bits, external) of {} internal + {} "
                   "external\n",
                   memoryBitsPerPe, matrixBitsPerPe, internalCapacity, externalCapacity);
  if (alwaysUncertainObjects > 0)
    s += fmt::format("{} object(s) have bounds that do not close at these widths: every pixel that may "
                     "hit them is uncertain\n",
                     alwaysUncertainObjects);
  return s;
}

nlohmann::json PrimaryPass::Json() const {
  return {{"plan", plan.Json()},
          {"cycles", cycles},
          {"hostSeconds", hostSeconds},
          {"modelledSeconds", modelledSeconds},
          {"realTimeFactor", hostSeconds > 0 ? modelledSeconds / hostSeconds : 0.0},
          {"recomputeSeconds", recomputeSeconds},
          {"uncertain", {{"overflow", overflowPixels}, {"grazing", grazingPixels},
                         {"nearTie", tiePixels}, {"recomputed", recomputedPixels}}}};
}

namespace {

Fixed Constant(double x, Format f) {
  return fixed::FromDouble(x, f, {fixed::Rounding::Nearest, fixed::OverflowPolicy::Saturate});
}

// The narrowest format with F fraction bits that holds x (a uni constant: a multiply by it
// costs one row per one bit).
Fixed Tight(double x, int frac) { return Constant(x, Format::Signed(IntBitsFor(std::abs(x)), frac)); }

}  // namespace

PrimaryPass RunPrimaryPass(const Scene& scene, const SimdOptions& options) {
  PrimaryPass pass;
  pass.plan = PlanPrimaryPass(scene, options);
  const PrimaryPlan& plan = pass.plan;
  const Camera& cam = scene.camera;
  const auto start = std::chrono::steady_clock::now();
  Machine m(MakeProfile(options), plan.virtualPes);
  const int F = plan.fracBits;
  const Format T = plan.t;
  const fixed::Policy saturate{fixed::Rounding::Floor, fixed::OverflowPolicy::Saturate};
  const PassFormats pf = FormatsOf(plan, scene);

  // The per-pixel matrix, in external memory in this order (docs/simd.md, "The matrix layout").
  Multi object(m, plan.object, "matrix.object", Space::External);
  Multi tBest(m, T, "matrix.t", Space::External);
  Multi d[3] = {Multi(m, plan.direction, "matrix.dx", Space::External),
                Multi(m, plan.direction, "matrix.dy", Space::External),
                Multi(m, plan.direction, "matrix.dz", Space::External)};
  Multi grazeFlag(m, bitserial::BoolFormat(), "matrix.grazing", Space::External);
  Multi tieFlag(m, bitserial::BoolFormat(), "matrix.nearTie", Space::External);

  // The host computes each pixel's eye ray and loads the directions (one plane per bit).
  const PrimaryRays rays(cam);
  {
    std::vector<int64_t> raw[3];
    for (auto& r : raw) r.resize(plan.virtualPes);
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const Vec3 dir = rays.At(x, y).direction;
        for (int k = 0; k < 3; ++k)
          raw[k][size_t(y) * cam.width + x] = std::llround(std::ldexp(dir[k], plan.dirFracBits));
      }
    for (int k = 0; k < 3; ++k) d[k].LoadRaw(raw[k]);
  }
  const Fixed tMax{T, T.MaxRaw()};
  tBest = Broadcast(m, tMax);
  // Near ties per pair (docs/simd.md, "Uncertain pixels"): the final best k and another hit j
  // are tied when t_j − e_j <= t_k + e_k. Each PE keeps lowBest = t − e of its current best
  // and otherLow, the least t − e of every other hit so far; a displaced best's low joins
  // otherLow. bestUnsure: the current best was itself uncertain (its e does not hold).
  Multi tGraze = Broadcast(m, tMax), otherLow = Broadcast(m, tMax), lowBest = Broadcast(m, tMax);
  Multi bestUnsure = Broadcast(m, Fixed{bitserial::BoolFormat(), 0});

  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const ObjectBounds bounds = BoundObject(scene, int(i), pf);
    const Candidate c = TestObject(m, scene, int(i), d, pf, bounds);
    // t − e_i with e_i rounded up (an always-uncertain object's every hit is flagged, so its
    // e is never relied on); saturating down only widens the test.
    const double e = bounds.alwaysUncertain ? 0.0 : bounds.tError + pf.Ulp();
    Multi low;
    WithExpectedSaturation(m, [&] { low = Sub(c.t, Broadcast(m, Tight(e, F)), T, saturate); });
    Where(c.uncertain, [&] { tGraze = Min(tGraze, c.tLow, T); });
    const Multi closer = c.hit && (c.t < tBest);
    Where(c.hit && !closer, [&] { otherLow = Min(otherLow, low, T); });
    Where(closer, [&] {
      otherLow = Min(otherLow, lowBest, T);
      lowBest = low;
      bestUnsure = c.uncertain;
      tBest = c.t;
      object = Broadcast(m, Fixed{plan.object, fixed::BigInt(i + 1)});
    });
  }
  // A flagged candidate or another hit matters only if it may lie in front of the final
  // best's true t <= tBest + e_best (= 2·tBest − lowBest; tMax marks "none"; the limit's
  // exact format cannot overflow). An uncertain best is grazing itself.
  const Multi limit = tBest + (tBest - lowBest), none = Broadcast(m, tMax);
  grazeFlag = bestUnsure || ((tGraze <= limit) && (tGraze < none));
  tieFlag = (otherLow <= limit) && (otherLow < none);

  // Move the matrix to the host (charged to the host link).
  const std::vector<int64_t> objRaw = object.ReadRaw(), tRaw = tBest.ReadRaw(),
                             dRaw[3] = {d[0].ReadRaw(), d[1].ReadRaw(), d[2].ReadRaw()},
                             grazeRaw = grazeFlag.ReadRaw(), tieRaw = tieFlag.ReadRaw();
  m.Charge("hostRead", bitserial::HostTransferCost(1));  // the overflow flags
  pass.hostSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const bitserial::CycleReport& report = m.Report();
  pass.modelledSeconds = report.ModelledSeconds();
  pass.cycles = report.Json();
  const bitserial::PeMemory& mem = m.Memory();
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
                                pass.modelledSeconds, m.Profile().clockHz / 1e6, pass.hostSeconds,
                                pass.modelledSeconds / pass.hostSeconds);

  // The host side: decode the matrix, handle uncertain pixels.
  const auto hostStart = std::chrono::steady_clock::now();
  PrimaryMatrix& out = pass.matrix;
  out.width = cam.width, out.height = cam.height;
  out.hits.resize(plan.virtualPes);
  out.flags.assign(plan.virtualPes, 0);
  for (int64_t pe = 0; pe < plan.virtualPes; ++pe) {
    PrimaryHit& h = out.hits[pe];
    h.direction = Normalize(Vec3{std::ldexp(double(dRaw[0][pe]), -plan.dirFracBits),
                                 std::ldexp(double(dRaw[1][pe]), -plan.dirFracBits),
                                 std::ldexp(double(dRaw[2][pe]), -plan.dirFracBits)});
    h.object = int(objRaw[pe]) - 1;
    h.t = h.object >= 0 ? std::ldexp(double(tRaw[pe]), -F) : 0.0;
    uint32_t& fl = out.flags[pe];
    if (m.Overflow(pe) || m.DivideByZero(pe)) fl |= kOverflow;  // Invalid: √ of a miss
    if (grazeRaw[pe]) fl |= kGrazing;
    if (tieRaw[pe]) fl |= kNearTie;
    if (fl & kOverflow) ++pass.overflowPixels;
    if (fl & kGrazing) ++pass.grazingPixels;
    if (fl & kNearTie) ++pass.tiePixels;
  }
  const int64_t uncertain = std::count_if(out.flags.begin(), out.flags.end(), [](uint32_t f) { return f != 0; });
  if (options.uncertain == UncertainPolicy::kFail && uncertain > 0)
    throw UserError(fmt::format("--uncertain fail: {} uncertain pixel(s): {} overflow, {} grazing, {} near tie",
                                uncertain, pass.overflowPixels, pass.grazingPixels, pass.tiePixels));
  if (options.uncertain == UncertainPolicy::kRecompute && uncertain > 0) {
    TraceOptions trace;
    trace.depth = 1;
    const auto tracer = Tracer::Create(scene, trace);
    TraceStats stats;
    for (int64_t pe = 0; pe < plan.virtualPes; ++pe) {
      if (!out.flags[pe]) continue;
      out.hits[pe] = tracer->FirstHit(rays.At(int(pe % cam.width), int(pe / cam.width)), stats);
      out.flags[pe] |= kRecomputed;
      ++pass.recomputedPixels;
    }
  }
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
      // the wrong side of the surface so secondary rays re-hit it (SPEC §4). The host
      // refines t against the one object the array found (one double test, not N).
      if (hit.object >= 0) {
        const Scene& scene = tracer.GetScene();
        const double tMin = std::max(scene.camera.hither, 0.0);
        if (auto t = IntersectObject(scene, hit.object, scene.camera.from, hit.direction, tMin,
                                     tracer.Options().sphereTest))
          hit.t = *t;
      }
      out[size_t(y) * w + x] = tracer.ShadeFromPrimaryHit(hit, stats);
    }
}

}  // namespace zephyr::simd
