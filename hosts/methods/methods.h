// hosts/methods/methods.h — the four methods' entry points, for the table in
// hosts/methods/render.cpp (not for other rooms: they go through RunRender).
#pragma once

#include <optional>

#include "hosts/methods/output.h"

namespace zephyr {

// Fills out.image (and out.primary when options.dumpPrimary is set) and the method's typed
// results (out.hostWork, out.simd, out.farm).
using RenderMethod = void (*)(const Scene& scene, const RenderOptions& options, RenderOutput& out);

// For the methods that run under MPI: called before the scene is read. On a child rank it
// serves frames and ends the process (on a cluster the scene file exists only where the
// parent runs); on the parent it returns. UserError for fewer than 2 ranks or bad options.
using RenderChildEntry = void (*)(const RenderOptions& options);

// Runs on the process that writes the outputs, after RunRender's checks of the output paths
// and before the scene is read or any work starts: the method's check of its own options and
// of what it cannot do with the shared ones (e.g. dist has no --dump-primary; the checkpoint
// must not be another output). Throws UserError.
using RenderCheckOptions = void (*)(const RenderOptions& options);

struct RenderMethodEntry {
  const char* name;
  const char* description;
  RenderMethod render;
  RenderChildEntry child = nullptr;    // nullptr: the method runs in one process
  RenderCheckOptions check = nullptr;  // nullptr: nothing beyond the shared checks
  // The method's peak memory at the parent, bytes per image pixel, and what --dump-primary
  // adds: measured peaks (/usr/bin/time %M, 2048x2048, 8 spheres) with ~25 % margin,
  // docs/errors.md "Memory". RunRender refuses a run that cannot fit before any work.
  double bytesPerPixel = 0;
  double dumpBytesPerPixel = 0;
  bool usesArray = false;      // runs the SIMD pass on the emulated array (--machine applies)
  bool usesWavefront = false;  // traces the secondary rays on the array (--compact applies)
};

// What simd and array share (simd.cpp): the SIMD primary pass timed as the "primaryPass" phase
// with its cycle report printed; and, once the image is shaded, the pass and the host's work
// moved into `out` (--dump-primary's hits first, the matrix then emptied). `plan`: one the
// caller has made (PlanPrimaryPass; its time is the caller's to add to the phase), else the
// pass plans.
simd::PrimaryPass RunTimedPrimaryPass(const Scene& scene, const RenderOptions& options,
                                      RenderOutput& out,
                                      std::optional<simd::PrimaryPlan> plan = std::nullopt);
void KeepPrimaryPass(simd::PrimaryPass pass, const TraceStats& hostWork,
                     const RenderOptions& options, RenderOutput& out);

void RenderSeq(const Scene& scene, const RenderOptions& options, RenderOutput& out);   // seq.cpp
void RenderSimd(const Scene& scene, const RenderOptions& options, RenderOutput& out);  // simd.cpp
void RenderArray(const Scene& scene, const RenderOptions& options,
                 RenderOutput& out);                                                   // array.cpp
void RenderDist(const Scene& scene, const RenderOptions& options, RenderOutput& out);  // dist.cpp
void DistChildEntry(const RenderOptions& options);                                     // dist.cpp
void CheckDistOptions(const RenderOptions& options);                                   // dist.cpp
void RenderHetero(const Scene& scene, const RenderOptions& options,
                  RenderOutput& out);                   // hetero.cpp
void HeteroChildEntry(const RenderOptions& options);    // hetero.cpp
void CheckHeteroOptions(const RenderOptions& options);  // hetero.cpp

}  // namespace zephyr
