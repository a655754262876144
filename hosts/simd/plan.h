// hosts/simd/plan.h — the format planner of the SIMD primary pass (docs/simd.md, "The
// planner"): for one scene, the pass-wide formats and, per object, the bounds, formats and
// host set-up its array program runs with. The pass (hosts/simd/pass.h) takes all of them
// from here, and `zephyr plan` prints exactly these. The options it plans for (the policies,
// the width limits, SimdOptions): hosts/simd/options.h.
//
//   const PrimaryPlan plan = PlanPrimaryPass(scene, options);  // UserError if it cannot fit
//   plan.objects[i].bounds.tError, plan.objects[i].formats     // object i, as the pass uses it
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bitserial/profile.h"
#include "fixed/float.h"
#include "fixed/format.h"
#include "hosts/scene/scene.h"
#include "hosts/simd/bounds.h"
#include "hosts/simd/options.h"

namespace zephyr::simd {

// One chosen quantity of the plan: its format and why.
struct PlannedFormat {
  PlannedFormat() = default;
  PlannedFormat(std::string q, fixed::Format f, std::string r,
                std::optional<fixed::FloatFormat> ff = std::nullopt)
      : quantity(std::move(q)), format(f), reason(std::move(r)), floatFormat(ff) {}
  std::string quantity;
  fixed::Format format;
  std::string reason;
  // --number float: the quantity is a float of this format (`format` is then the fixed t it
  // ends in); FormatName() names the float.
  std::optional<fixed::FloatFormat> floatFormat;
  std::string FormatName() const { return floatFormat ? floatFormat->Name() : format.Name(); }
};

// What the host knows about one object before the pass (world-space eye), derived from the
// formats (docs/simd.md, "Error bounds"). Lengths in scene units.
struct ObjectBounds {
  ShapeKind kind = ShapeKind::kSphere;
  bool transformed = false;
  double farthest = 0;           // farthest point of the object from the eye
  double tError = 0;             // |t − t_exact| for a hit that is not flagged
  double slack = 0;              // a flagged candidate's true t is >= its computed t − slack
  double grazeBand = 0;          // |discriminant| (or |edge function|) below this is grazing
  int intBits = 1;               // widest integer part among the object's quantities
  bool alwaysUncertain = false;  // bounds degenerate at these widths: every candidate flagged
};

class ObjectProgram;  // hosts/simd/object.h: the host set-up and the array program

// One object as the pass runs it.
struct ObjectPlan {
  int index = 0;  // in scene.objects
  ObjectBounds bounds;
  std::vector<PlannedFormat> formats;  // every format its array program uses
  std::shared_ptr<const ObjectProgram> program;
  // 1.. for a polygon in exactly the same plane as another (exact::CoplanarPolygons; their t
  // is bit for bit the same, and a tie between them is decided by the lowest index, as the
  // exact reference does); 0 for every other object.
  int planeClass = 0;
  // The most its program (candidate and fold) holds at once above what lives through the
  // whole pass, in bits per virtual PE: measured by the planner (hosts/simd/program.h).
  int64_t temporaryBits = 0;
  const char* KindName() const;  // sphere, ellipsoid, polygon, cone
};

// The format planner's choice for one scene (docs/simd.md: model no more than a scene needs).
struct PrimaryPlan {
  int width = 0, height = 0;
  int64_t virtualPes = 0;  // every pixel (a refine pass: every pixel it runs on)
  int layers = 0;          // over every array pass
  // Array passes (docs/simd.md, "Several array passes"): when the layers of every virtual PE
  // leave each too little memory, pass k runs PEs [k·pesPerPass, (k+1)·pesPerPass) (whole
  // rows of the image), each with at most layersPerPass layers, by which memory is split.
  int passes = 1;
  int64_t pesPerPass = 0;
  int layersPerPass = 0;
  int distIntBits = 0;  // integer bits of every distance (eye-to-object, t)
  int fracBits = 0;     // fraction bits of lengths, products, discriminants, t
  int dirFracBits = 0;  // fraction bits of the direction components
  int objectBits = 0;   // width of the object index (+1, 0 = none)
  fixed::Format direction, length, t, object;
  PassFormats pass;            // the formats every object's program shares
  double tErrorBound = 0;      // |t_fixed − t_exact| for a certain (unflagged) hit: the largest
                               // per-object bound (always-uncertain objects excluded)
  double grazingFraction = 0;  // grazing band G = max((r·this)², 2·e_disc), per object
  // The pass-wide table: each quantity at the widest format any object's program uses it in
  // (the per-object formats are in `objects`).
  std::vector<PlannedFormat> formats;
  std::vector<ObjectPlan> objects;  // one per scene object, in scene order
  int64_t memoryBitsPerPe = 0;      // the program's peak per virtual PE (measured on one PE)
  int64_t matrixBitsPerPe = 0;      // the per-pixel matrix in external memory
  int64_t internalCapacity = 0, externalCapacity = 0;  // bits per virtual PE (in a pass)
  int alwaysUncertainObjects = 0;  // objects whose bounds degenerate at these widths (every
                                   // pixel that may hit them is flagged)
  int planeClasses = 0;            // planes holding more than one polygon (ObjectPlan::planeClass)
  NumberSystem number = NumberSystem::kFixed;  // of the intersections (--number)
  fixed::FloatFormat floatFormat;              // with kFloat: their format (pass.floatFormat)
  nlohmann::json Json() const;                 // the report's plan (pass-wide)
  nlohmann::json ObjectsJson() const;          // per object: kind, bounds, formats
  std::string Text() const;  // `zephyr plan`'s output, per-object formats included
};

// Throws UserError when one layer of the machine cannot hold the program at these formats
// (or one row of the image does not fit a pass), or the requested widths are beyond the
// pass's limits. An image whose layers do not fit at once is planned in several passes, by
// what the program allocates (run once on one virtual PE; memoryBitsPerPe).
PrimaryPlan PlanPrimaryPass(const Scene& scene, const SimdOptions& options);

// Splits the plan's PEs into array passes of whole units of `unit` PEs (the image's rows; 1
// for a refine pass) with as many layers each as leave every virtual PE `needBits` bits of
// memory, the units spread evenly (sets passes, pesPerPass, layersPerPass, layers and the
// capacities). UserError if one unit needs more layers than that. The planner calls it with
// what the program allocates (docs/simd.md, "Several array passes").
void SplitPasses(PrimaryPlan& plan, const bitserial::MachineProfile& profile, int64_t unit,
                 int64_t needBits);

// The plan of a refine pass (docs/simd.md, "Refine pass"): `pixels` virtual PEs (the first
// pass's uncertain pixels, compacted into as few layers as they need) at the first plan's
// integer bits and its fraction bits plus `extraBits` (capped at the pass's limits), with
// the bounds' nominal sizes kept at the first pass's (PassFormats::nominalUlp). UserError as
// PlanPrimaryPass.
PrimaryPlan PlanRefinePass(const Scene& scene, const SimdOptions& options, const PrimaryPlan& first,
                           int64_t pixels, int extraBits);

}  // namespace zephyr::simd
