// hosts/simd/plan.cpp — the format planner of the SIMD primary pass (hosts/simd/plan.h,
// docs/simd.md "The planner"): the scene's range, the pass-wide formats, each object's plan
// (hosts/simd/<kind>.cpp), the memory check, and the plan as JSON and text.
#include "hosts/simd/plan.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "fixed/check.h"
#include "hosts/simd/object.h"
#include "hosts/simd/program.h"
#include "hosts/trace/exact.h"

namespace zephyr::simd {

using fixed::Format;

ObjectFrame MakeObjectFrame(const Primitive& p, const Vec3& eye) {
  ObjectFrame f;
  const Affine t = p.transform ? *p.transform : Affine{};
  const Affine inv = t.Inverse();
  double fn = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      f.a[i][j] = inv.m[i][j];
      fn += t.m[i][j] * t.m[i][j];
      f.rowSum[i] += std::abs(inv.m[i][j]);
    }
    f.ddMax += f.rowSum[i] * f.rowSum[i];
  }
  f.forwardNorm = std::sqrt(fn);
  f.eye = inv.ApplyPoint(eye);
  return f;
}

double InverseFrobenius(const Primitive& p) {
  if (!p.transform) return 1;
  const Affine inv = p.transform->Inverse();
  double norm = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) norm += inv.m[r][c] * inv.m[r][c];
  return std::sqrt(norm);
}

const char* ObjectPlan::KindName() const {
  switch (bounds.kind) {
    case ShapeKind::kSphere:
      return bounds.transformed ? "ellipsoid" : "sphere";
    case ShapeKind::kPolygon:
      return "polygon";
    case ShapeKind::kCone:
      return "cone";
  }
  return "?";
}

namespace {

// The pass reads t, the object index and the direction of each pixel to the host as one
// 64-bit word each (Multi::ReadRaw), so the planner keeps those formats within 64 bits.
constexpr int kMaxMatrixWordBits = 64;

ObjectExtent ExtentOf(const Primitive& p, const Vec3& eye) {
  switch (p.Kind()) {
    case ShapeKind::kSphere:
      return p.transform ? EllipsoidExtent(p, eye) : SphereExtent(p, eye);
    case ShapeKind::kPolygon:
      return PolygonExtent(p, eye);
    case ShapeKind::kCone:
      return ConeExtent(p, eye);
  }
  ZEPHYR_CHECK(false);
  return {};
}

ObjectPlan PlanObject(const Scene& scene, int index, const PassFormats& pf,
                      const std::vector<int>& planes) {
  const Primitive& p = scene.objects[index];
  const Vec3& eye = scene.camera.from;
  ObjectPlan plan;
  if (pf.floatFormat) {
    // --number float has a program for spheres only (docs/simd.md, "Floating point on the array").
    if (p.Kind() != ShapeKind::kSphere || p.transform)
      throw UserError(fmt::format(
          "{}: the float number system supports spheres only; this object is a {} "
          "(use --number fixed)",
          p.where.ToString(),
          p.transform && p.Kind() == ShapeKind::kSphere ? "transformed sphere (an ellipsoid)"
                                                        : ShapeKindName(p.Kind())));
    plan = PlanFloatSphere(p, eye, pf);
    plan.index = index;
    return plan;
  }
  switch (p.Kind()) {
    case ShapeKind::kSphere:
      plan = p.transform ? PlanEllipsoid(p, eye, pf) : PlanSphere(p, eye, pf);
      break;
    case ShapeKind::kPolygon:
      plan = PlanPolygon(p, eye, pf, planes[index] >= 0 ? scene.objects[planes[index]] : p);
      break;
    case ShapeKind::kCone:
      plan = PlanCone(p, eye, pf);
      break;
  }
  plan.index = index;
  plan.bounds.transformed = bool(p.transform);
  return plan;
}

// The scene's range: the farthest point of an object from the eye and the smallest feature.
struct SceneRange {
  double farthest = 1, rMin = 1e300;
  const Primitive* farthestObject = nullptr;  // for messages
};

SceneRange RangeOf(const Scene& scene) {
  SceneRange r;
  for (const Primitive& p : scene.objects) {
    const ObjectExtent e = ExtentOf(p, scene.camera.from);
    if (!(e.farthest <= r.farthest)) r.farthestObject = &p;
    r.farthest = std::max(r.farthest, e.farthest);
    r.rMin = std::min(r.rMin, e.feature);
  }
  if (scene.objects.empty() || !(r.rMin > 0) || r.rMin > 1e299) r.rMin = 1;
  return r;
}

// The widths: integer bits for the farthest distance (one more for tca ± root); fraction
// bits so that the t error bound (≈ 60·D·2^-F, docs/simd.md) is at most 1/64 of the
// smallest feature, never coarser than 2^-10, and so that t (s L.F, 1 + L + F bits) fits
// the 64-bit word the host reads per pixel (a far scene gets fewer fraction bits: wider
// bounds, more uncertain pixels recomputed on the host); the user's overrides win. Widths
// the pass cannot hold are a UserError naming the farthest object, never an abort.
void ChooseWidths(PrimaryPlan& plan, const SceneRange& range, const FormatOverrides& o) {
  plan.distIntBits = o.intBits >= 0 ? o.intBits : IntBitsFor(range.farthest) + 1;
  const int wanted = std::clamp(CeilLog2(64.0 * 60.0 * range.farthest / range.rMin), 10, 40);
  const int planned = std::max(10, std::min(wanted, kMaxMatrixWordBits - 1 - plan.distIntBits));
  plan.fracBits = o.fracBits >= 0 ? o.fracBits : planned;
  plan.dirFracBits = o.dirFracBits >= 0 ? o.dirFracBits : plan.fracBits;
  const std::string where =
      range.farthestObject
          ? fmt::format("{}: the {} {:.4g} from the eye; ", range.farthestObject->where.ToString(),
                        ShapeKindName(range.farthestObject->Kind()), range.farthest)
          : std::string();
  // A width the user gave is named as the one asked for (not as the scene's fault; the
  // command line refuses these as it is parsed, naming the flag).
  for (const auto& [what, given, limit] :
       {std::tuple{"fraction bits", o.fracBits, kMaxFracBits},
        std::tuple{"direction fraction bits", o.dirFracBits, kMaxDirFracBits},
        std::tuple{"integer bits", o.intBits, kMaxIntBits}})
    if (given > limit)
      throw UserError(fmt::format(
          "{} {} asked for: more than the {} bits the primary pass supports (docs/simd.md)", given,
          what, limit));
  if (plan.fracBits > kMaxFracBits || plan.dirFracBits > kMaxDirFracBits ||
      plan.distIntBits > kMaxIntBits)
    throw UserError(
        fmt::format("{}formats too wide for the primary pass: {} integer bits, {} fraction "
                    "bits, {} direction fraction bits (limits 40, 56, 60)",
                    where, plan.distIntBits, plan.fracBits, plan.dirFracBits));
  if (1 + plan.distIntBits + plan.fracBits > kMaxMatrixWordBits)
    throw UserError(
        fmt::format("{}t would be s{}.{}, {} bits, more than the {} bits the host reads per "
                    "pixel; use fewer fraction or integer bits",
                    where, plan.distIntBits, plan.fracBits, 1 + plan.distIntBits + plan.fracBits,
                    kMaxMatrixWordBits));
}

// Every format an object's program uses must be one the operations support (1..kMaxWidth
// bits); a scene that needs wider (a transform that shrinks an object by 1e-30, say) is a
// UserError naming the object and the format.
void CheckObjectFormats(const PrimaryPlan& plan, const Scene& scene) {
  for (const ObjectPlan& o : plan.objects)
    for (const PlannedFormat& f : o.formats)
      if (!f.format.IsValid())
        throw UserError(
            fmt::format("{}: the {}'s {} would need {} bits ({}), more than the {} the "
                        "array's operations support; scale or move the object",
                        scene.objects[o.index].where.ToString(), o.KindName(), f.quantity,
                        f.format.Width(), f.format.Name(), fixed::kMaxWidth));
  for (const PlannedFormat& f : plan.formats)
    if (!f.format.IsValid())
      throw UserError(
          fmt::format("the primary pass's {} would need {} bits ({}), more than the {} the "
                      "array's operations support",
                      f.quantity, f.format.Width(), f.format.Name(), fixed::kMaxWidth));
}

// The pass-wide table, derived from the object programs (each reports every format it uses,
// ObjectPlan::formats): the matrix's own rows (direction, t, object index) and, per kind and
// quantity, the widest format any object of that kind uses it in, with that object's reason.
// A scene of polygons has no sphere row.
void SummaryTable(PrimaryPlan& plan, const Scene& scene, const SceneRange& range) {
  plan.formats = {{"direction d (x,y,z)", plan.direction,
                   plan.number == NumberSystem::kFloat
                       ? "the matrix's, fraction bits = max(F, the float's precision); the pass "
                         "reads them in float"
                       : "unit components in [-1,1]; fraction bits = F"}};
  const auto width = [](const PlannedFormat& f) {
    return f.floatFormat ? f.floatFormat->Width() : f.format.Width();
  };
  struct Row {
    PlannedFormat format;
    int users = 0;
  };
  std::vector<std::string> order;
  std::map<std::string, Row> rows;
  for (const ObjectPlan& o : plan.objects)
    for (const PlannedFormat& f : o.formats) {
      const std::string key = std::string(o.KindName()) + ": " + f.quantity;
      auto [it, fresh] = rows.try_emplace(key, Row{f, 0});
      if (fresh) order.push_back(key);
      ++it->second.users;
      if (width(f) > width(it->second.format)) it->second.format = f;
    }
  for (const std::string& key : order) {
    PlannedFormat f = rows.at(key).format;
    f.quantity = key;
    if (rows.at(key).users > 1)
      f.reason += fmt::format(" (the widest of {} objects')", rows.at(key).users);
    plan.formats.push_back(f);
  }
  plan.formats.push_back(
      {"t (the matrix)", plan.t,
       fmt::format("the farthest point of an array object is {:.4g} from the eye",
                   range.farthest)});
  plan.formats.push_back(
      {"object index + 1", plan.object, fmt::format("{} objects, 0 = none", scene.objects.size())});
}

// The PE memory of one layer of `profile`'s `layers`-layer machine, as one PE's own (a
// virtual PE of it has exactly that: bitserial/memory.h).
bitserial::MachineProfile OneLayerOf(bitserial::MachineProfile profile, int64_t layers) {
  profile.internalBitsPerPe /= layers;
  profile.externalBitsPerPe /= layers;
  return profile;
}

// A PE of `profile` with no limit to its external memory: the program's allocation measured
// there when one layer of the profile cannot hold it (so that the message can say how much it
// needs).
bitserial::MachineProfile Roomy(bitserial::MachineProfile profile) {
  profile.externalBitsPerPe = int64_t(1) << 40;
  return profile;
}

// The array passes, from what the program allocates (plan.memoryBitsPerPe, measured). With n
// layers each virtual PE has floor(internal / n) + floor(external / n) bits
// (bitserial/memory.h); when the image's layers leave too few, the image runs in several
// array passes (docs/simd.md, "Several array passes"), each over as few whole units of `unit`
// PEs (rows of the image; single PEs of a refine pass) as balance the passes, with as many
// layers as still hold the program. The split by the sum is checked by running the program on
// one PE of a pass's capacities (first fit may find no place for a variable the sum has room
// for); where it does not fit, the passes split again with a sixteenth more. UserError (from
// SplitPasses) when a single unit needs more layers than fit.
void FitPasses(PrimaryPlan& plan, const Scene& scene, const bitserial::MachineProfile& profile,
               int64_t unit) {
  const auto fits = [&] {
    if (plan.layersPerPass == 1) return true;  // measured on one layer
    try {
      MeasureProgram(plan, scene.camera, OneLayerOf(profile, plan.layersPerPass));
      return true;
    } catch (const UserError&) {
      return false;
    }
  };
  int64_t need = plan.memoryBitsPerPe;
  for (SplitPasses(plan, profile, unit, need); !fits(); SplitPasses(plan, profile, unit, need))
    need += std::max<int64_t>(1, need / 16);
}

}  // namespace

namespace {

// --number float without --float-format: 8 exponent bits (11 when the squares of the scene's
// distances need them) and as many fraction bits as make the float's absolute error at the
// farthest distance about the fixed pass's ulp (p ≈ F + log2(farthest)), 10..52; subnormals
// as the profile's machine had them (floatSubnormals).
fixed::FloatFormat PlanFloatFormat(const PrimaryPlan& plan, const SceneRange& range,
                                   const bitserial::MachineProfile& profile) {
  const int e = 2 * CeilLog2(range.farthest + 1) + 4 < 127 ? 8 : 11;
  const int m = std::clamp(plan.fracBits + CeilLog2(range.farthest + 1) - 1, 10, 52);
  return {e, m, profile.floatSubnormals};
}

// The formats and object programs of a plan over `virtualPes` PEs whose bounds' nominal
// sizes refer to `nominalUlp` (0: its own); no memory yet.
PrimaryPlan PlanFormats(const Scene& scene, const SimdOptions& options,
                        const bitserial::MachineProfile& profile, int64_t virtualPes,
                        double nominalUlp) {
  const Camera& cam = scene.camera;
  PrimaryPlan plan;
  plan.width = cam.width, plan.height = cam.height;
  plan.virtualPes = virtualPes;
  plan.layers = int((plan.virtualPes + profile.physicalPes - 1) / profile.physicalPes);
  const SceneRange range = RangeOf(scene);
  ChooseWidths(plan, range, options.formats);
  if (options.number == NumberSystem::kFloat) {
    plan.number = NumberSystem::kFloat;
    plan.floatFormat =
        options.floatFormat ? *options.floatFormat : PlanFloatFormat(plan, range, profile);
    plan.pass.floatFormat = plan.floatFormat;
    // The matrix's direction (the host shades with it) keeps the float's precision too, so
    // the image is not limited by a coarser direction than the pass computed with.
    if (options.formats.dirFracBits < 0)
      plan.dirFracBits = std::clamp(plan.floatFormat.Precision(), plan.dirFracBits, 60);
  }
  const int L = plan.distIntBits, F = plan.fracBits;
  plan.objectBits = std::max(1, CeilLog2(double(scene.objects.size()) + 1));
  plan.direction = Format::Signed(1, plan.dirFracBits);
  plan.length = Format::Signed(L, F);
  plan.t = Format::Signed(L, F);
  plan.object = Format::Unsigned(plan.objectBits, 0);
  plan.pass.fracBits = plan.fracBits;
  plan.pass.dirFracBits = plan.dirFracBits;
  plan.pass.t = plan.t;
  // A hither beyond every object hides them all; held to just past the farthest one (t never
  // exceeds it) so that it fits the pass's formats: `hither 1e30` once aborted the pass.
  plan.pass.hither = std::min(std::max(cam.hither, 0.0), 2 * range.farthest + 1);
  plan.pass.nominalUlp = nominalUlp;
  // Each object's bounds, formats and program, derived from these formats (docs/simd.md,
  // "Error bounds").
  plan.grazingFraction = 1.0 / 8;
  const std::vector<int> planes = exact::CoplanarPolygons(scene);
  std::vector<int> members(scene.objects.size(), 0), classOf(scene.objects.size(), 0);
  for (int r : planes)
    if (r >= 0) ++members[r];
  for (size_t i = 0; i < scene.objects.size(); ++i)
    if (planes[i] == int(i) && members[i] > 1) classOf[i] = ++plan.planeClasses;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    plan.objects.push_back(PlanObject(scene, int(i), plan.pass, planes));
    if (planes[i] >= 0) plan.objects.back().planeClass = classOf[planes[i]];
    const ObjectBounds& b = plan.objects.back().bounds;
    if (!b.alwaysUncertain)
      plan.tErrorBound = std::max(plan.tErrorBound, b.tError);
    else
      ++plan.alwaysUncertainObjects;
  }
  SummaryTable(plan, scene, range);
  CheckObjectFormats(plan, scene);
  plan.matrixBitsPerPe = plan.objectBits + plan.t.Width() + 3 * plan.direction.Width() + 2;
  return plan;
}

// Why a program one layer cannot hold is refused: what it needs, the part that needs most,
// and the fraction bits that would fit (`fitsAt(F)`: the plan at F fraction bits fits).
std::string NotOneLayer(const PrimaryPlan& plan, const Scene& scene, const ProgramMemory& memory,
                        const bitserial::MachineProfile& profile, const std::string& full,
                        const std::function<bool(int)>& fitsAt) {
  const auto widest = std::max_element(memory.objectBits.begin(), memory.objectBits.end());
  std::string most;
  if (widest != memory.objectBits.end()) {
    const ObjectPlan& o = plan.objects[size_t(widest - memory.objectBits.begin())];
    most = fmt::format(", and at most {} more for one object's program (the {} at {})", *widest,
                       o.KindName(), scene.objects[o.index].where.ToString());
  }
  // The widest F in [kMinFracBits, F - 1] that fits (fewer bits never need more memory).
  int lo = kMinFracBits - 1,
      hi = plan.fracBits;  // fitsAt(lo) or lo is below the range; !fitsAt(hi)
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (fitsAt(mid) ? lo : hi) = mid;
  }
  return fmt::format(
      "the primary pass does not fit one layer of the {} array: it needs {} bits per virtual PE "
      "(the matrix, "
      "directions and trackers {} bits, t and lengths {}{}) but a PE has {} internal + {} external "
      "bits ({}); {}",
      profile.name, memory.peakBits, memory.baseBits, plan.t.Name(), most,
      profile.internalBitsPerPe, profile.externalBitsPerPe, full,
      lo >= kMinFracBits ? fmt::format("{} fraction bits would fit", lo)
                         : fmt::format("no width down to {} fraction bits fits", kMinFracBits));
}

// A plan over `virtualPes` PEs, split into passes of whole units of `unit` PEs when the
// array is full, whose bounds' nominal sizes refer to `nominalUlp` (0: its own). Its memory
// is what its program allocates (MeasureProgram), each object's temporaries with it.
PrimaryPlan PlanFor(const Scene& scene, const SimdOptions& options, int64_t virtualPes,
                    int64_t unit, double nominalUlp) {
  const bitserial::MachineProfile profile = MachineProfileOf(options);
  PrimaryPlan plan = PlanFormats(scene, options, profile, virtualPes, nominalUlp);
  // On one layer of the machine, every variable where the pass places it (the matrix in
  // external memory): the program fits one layer exactly when this run does.
  ProgramMemory memory;
  std::string full;  // why one layer cannot hold it
  try {
    memory = MeasureProgram(plan, scene.camera, profile);
  } catch (const UserError& e) {
    full = e.what();
    memory = MeasureProgram(plan, scene.camera, Roomy(profile));
  }
  for (size_t i = 0; i < plan.objects.size(); ++i)
    plan.objects[i].temporaryBits = memory.objectBits[i];
  plan.memoryBitsPerPe = memory.peakBits;
  if (!full.empty()) {
    const auto fitsAt = [&](int fracBits) {
      SimdOptions narrower = options;
      narrower.formats.fracBits = fracBits;
      narrower.formats.dirFracBits = std::min(fracBits, plan.dirFracBits);
      try {
        MeasureProgram(PlanFormats(scene, narrower, profile, virtualPes, nominalUlp), scene.camera,
                       profile);
        return true;
      } catch (const UserError&) {
        return false;
      }
    };
    throw UserError(NotOneLayer(plan, scene, memory, profile, full, fitsAt));
  }
  FitPasses(plan, scene, profile, unit);
  return plan;
}

}  // namespace

void SplitPasses(PrimaryPlan& plan, const bitserial::MachineProfile& profile, int64_t unit,
                 int64_t needBits) {
  const auto capacity = [&](int64_t layers) {
    return profile.internalBitsPerPe / layers + profile.externalBitsPerPe / layers;
  };
  const int64_t p = profile.physicalPes;
  // The most layers a pass may have: capacity(n) falls with n.
  int64_t most = (plan.virtualPes + p - 1) / p;
  if (capacity(most) < needBits) {
    int64_t lo = 1, hi = most;  // capacity(lo) >= needBits > capacity(hi)
    while (hi - lo > 1) {
      const int64_t mid = (lo + hi) / 2;
      (capacity(mid) >= needBits ? lo : hi) = mid;
    }
    most = lo;
  }
  const int64_t units = (plan.virtualPes + unit - 1) / unit;
  const int64_t unitsFit = most * p / unit;
  if (unitsFit == 0)
    throw UserError(
        fmt::format("a row of {} pixels does not fit one pass of the {} array: each virtual PE "
                    "needs about {} bits, so at "
                    "most {} layer(s) ({} PEs) per pass; use a narrower image or fewer bits "
                    "(--frac-bits, --int-bits)",
                    unit, profile.name, needBits, most, most * p));
  plan.passes = int((units + unitsFit - 1) / unitsFit);
  const int64_t perPass = (units + plan.passes - 1) / plan.passes;  // balanced; <= unitsFit
  plan.pesPerPass = std::min(plan.virtualPes, perPass * unit);
  plan.layersPerPass = int((plan.pesPerPass + p - 1) / p);
  const int64_t lastPes = plan.virtualPes - int64_t(plan.passes - 1) * plan.pesPerPass;
  plan.layers = (plan.passes - 1) * plan.layersPerPass + int((lastPes + p - 1) / p);
  plan.internalCapacity = profile.internalBitsPerPe / plan.layersPerPass;
  plan.externalCapacity = profile.externalBitsPerPe / plan.layersPerPass;
}

PrimaryPlan PlanPrimaryPass(const Scene& scene, const SimdOptions& options) {
  return PlanFor(scene, options, int64_t(scene.camera.width) * scene.camera.height,
                 scene.camera.width, 0);
}

PrimaryPlan PlanRefinePass(const Scene& scene, const SimdOptions& options, const PrimaryPlan& first,
                           int64_t pixels, int extraBits) {
  SimdOptions wide = options;
  // As many more bits as still fit t's 64-bit word (a far scene may have none to add).
  const int fracBits =
      std::min({first.fracBits + extraBits, 56, kMaxMatrixWordBits - 1 - first.distIntBits});
  wide.formats = {fracBits, std::min(first.dirFracBits + extraBits, 60), first.distIntBits};
  if (first.number == NumberSystem::kFloat) {
    fixed::FloatFormat f = first.floatFormat;
    f.fracBits = std::min({f.fracBits + extraBits, 52, 63 - f.expBits});
    wide.floatFormat = f;
  }
  return PlanFor(scene, wide, std::max<int64_t>(pixels, 1), 1, first.pass.Ulp());
}

nlohmann::json PrimaryPlan::Json() const {
  nlohmann::json j = {{"width", width},
                      {"height", height},
                      {"virtualPes", virtualPes},
                      {"layers", layers},
                      {"passes", passes},
                      {"pesPerPass", pesPerPass},
                      {"layersPerPass", layersPerPass},
                      {"distIntBits", distIntBits},
                      {"fracBits", fracBits},
                      {"dirFracBits", dirFracBits},
                      {"objectBits", objectBits},
                      {"tErrorBound", tErrorBound},
                      {"grazingFraction", grazingFraction},
                      {"memoryBitsPerPe", memoryBitsPerPe},
                      {"matrixBitsPerPe", matrixBitsPerPe},
                      {"internalCapacity", internalCapacity},
                      {"externalCapacity", externalCapacity},
                      {"alwaysUncertainObjects", alwaysUncertainObjects},
                      {"number", kNumberSystemNames.NameOf(number)}};
  if (number == NumberSystem::kFloat) j["floatFormat"] = floatFormat.Name();
  for (const PlannedFormat& f : formats)
    j["formats"].push_back(
        {{"quantity", f.quantity}, {"format", f.FormatName()}, {"reason", f.reason}});
  return j;
}

nlohmann::json PrimaryPlan::ObjectsJson() const {
  nlohmann::json all = nlohmann::json::array();
  for (const ObjectPlan& o : objects) {
    const ObjectBounds& b = o.bounds;
    auto finite = [](double x) {
      return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json("inf");
    };
    nlohmann::json j = {{"index", o.index},
                        {"kind", o.KindName()},
                        {"farthest", b.farthest},
                        {"tError", finite(b.tError)},
                        {"slack", finite(b.slack)},
                        {"grazeBand", b.grazeBand},
                        {"alwaysUncertain", b.alwaysUncertain},
                        {"temporaryBits", o.temporaryBits}};
    for (const PlannedFormat& f : o.formats)
      j["formats"].push_back(
          {{"quantity", f.quantity}, {"format", f.FormatName()}, {"reason", f.reason}});
    all.push_back(j);
  }
  return all;
}

std::string PrimaryPlan::Text() const {
  std::string s = fmt::format("{}x{} pixels = {} virtual PEs in {} layer(s)\n", width, height,
                              virtualPes, layers);
  if (passes > 1)
    s +=
        fmt::format("the array is full: {} array passes of up to {} virtual PEs ({} layers) each\n",
                    passes, pesPerPass, layersPerPass);
  for (const PlannedFormat& f : formats)
    s += fmt::format("  {:<34} {:<8} {}\n", f.quantity, f.FormatName(), f.reason);
  if (number == NumberSystem::kFloat)
    s += fmt::format(
        "number system float: the intersections in bit-serial float {} (directions, f·d, f×d, "
        "squares, "
        "disc, √disc, t0/t1), t then in the fixed format above\n",
        floatFormat.Name());
  const bool quadrics = std::any_of(objects.begin(), objects.end(), [](const ObjectPlan& o) {
    return o.bounds.kind != ShapeKind::kPolygon;
  });
  s += fmt::format(
      "error bound on t (certain pixels): {:.3g} (the largest object's e); near tie per pair: "
      "|t_i - t_j| <= e_i + e_j; grazing {}\n",
      tErrorBound,
      quadrics ? fmt::format("when disc < max((r/{:g})^2, 2 x its error bound), per object",
                             1 / grazingFraction)
               : std::string("within each object's band of its edges (per object below)"));
  s += fmt::format(
      "memory per virtual PE: {} bits at the peak (matrix {} bits, {}) of {} internal + {} "
      "external\n",
      memoryBitsPerPe, matrixBitsPerPe, externalCapacity > 0 ? "external" : "internal",
      internalCapacity, externalCapacity);
  if (alwaysUncertainObjects > 0)
    s += fmt::format(
        "{} object(s) have bounds that do not close at these widths: every pixel that may "
        "hit them is uncertain\n",
        alwaysUncertainObjects);
  // Per object, as the pass runs it: objects with the same kind and formats share one row
  // group (their index ranges, and the largest t error and grazing band among them).
  struct Group {
    std::vector<int> indices;
    double tError = 0, band = 0;
    int64_t temporaryBits = 0;
    const ObjectPlan* first = nullptr;
  };
  std::map<std::string, Group> groups;
  std::vector<std::string> order;
  for (const ObjectPlan& o : objects) {
    std::string key = o.KindName();
    for (const PlannedFormat& f : o.formats) key += "|" + f.FormatName();
    auto [it, fresh] = groups.try_emplace(key);
    if (fresh) order.push_back(key), it->second.first = &o;
    it->second.indices.push_back(o.index);
    it->second.tError = std::max(it->second.tError, o.bounds.tError);
    it->second.band = std::max(it->second.band, o.bounds.grazeBand);
    it->second.temporaryBits = std::max(it->second.temporaryBits, o.temporaryBits);
  }
  s += fmt::format("per object ({} object(s), {} group(s) of equal formats):\n", objects.size(),
                   order.size());
  for (const std::string& key : order) {
    const Group& g = groups[key];
    std::string which;
    for (size_t k = 0; k < g.indices.size(); ++k) {
      size_t e = k;
      while (e + 1 < g.indices.size() && g.indices[e + 1] == g.indices[e] + 1) ++e;
      which += fmt::format("{}{}", which.empty() ? "" : ",",
                           e == k ? fmt::format("{}", g.indices[k])
                                  : fmt::format("{}-{}", g.indices[k], g.indices[e]));
      k = e;
    }
    s += fmt::format(
        "  {} x{} (objects {}): t error <= {:.3g}, grazing band {:.3g}{}, temporaries {} bits\n",
        g.first->KindName(), g.indices.size(), which, g.tError, g.band,
        std::isfinite(g.tError) ? "" : " (always uncertain)", g.temporaryBits);
    for (const PlannedFormat& f : g.first->formats)
      s += fmt::format("    {:<26} {:<8} {}\n", f.quantity, f.FormatName(), f.reason);
  }
  return s;
}

}  // namespace zephyr::simd
