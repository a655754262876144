// hosts/methods/render.cpp — the method table, reading the scene, writing the outputs.
#include "hosts/methods/render.h"

#include <algorithm>
#include <cstdio>
#include <fstream>

#include "fixed/check.h"
#include "hosts/io/output_file.h"
#include "hosts/methods/farmed.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/methods/methods.h"
#include "hosts/methods/phases.h"
#include "hosts/methods/report.h"
#include "hosts/scene/nff.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {

namespace {

// The table of methods (docs/background.md, "The four methods").
constexpr RenderMethodEntry kMethods[] = {
    {"seq", "sequential: the host traces every ray in floating point", RenderSeq, nullptr, nullptr,
     /*bytesPerPixel=*/32, /*dumpBytesPerPixel=*/110, /*usesArray=*/false},
    {"simd",
     "SIMD/sequential: primary rays on the emulated array in fixed point, secondary rays on "
     "the host",
     RenderSimd, nullptr, nullptr, /*bytesPerPixel=*/104, /*dumpBytesPerPixel=*/60,
     /*usesArray=*/true},
    {"array",
     "all rays on the array: the SIMD primary pass, then every secondary and shadow ray on the "
     "emulated array bounce by bounce; the host shades the local term from its records",
     // 295 bytes per pixel measured at 2048x2048 (docs/errors.md, "Memory").
     RenderArray, nullptr, nullptr, /*bytesPerPixel=*/400, /*dumpBytesPerPixel=*/60,
     /*usesArray=*/true, /*usesWavefront=*/true},
    {"dist",
     "distributed: under mpirun, children trace whole F×F frames handed out on demand "
     "(bit-identical to seq)",
     RenderDist, DistChildEntry, CheckDistOptions, /*bytesPerPixel=*/64, /*dumpBytesPerPixel=*/0,
     /*usesArray=*/false},
    {"hetero",
     "heterogeneous: the SIMD primary pass at the parent, children shade the frames with a hit "
     "(under mpirun; bit-identical to simd)",
     RenderHetero, HeteroChildEntry, CheckHeteroOptions, /*bytesPerPixel=*/122,
     /*dumpBytesPerPixel=*/60,
     /*usesArray=*/true},
};

}  // namespace

std::vector<std::string> RenderMethodNames() {
  std::vector<std::string> names;
  for (const RenderMethodEntry& m : kMethods) names.push_back(m.name);
  std::sort(names.begin(), names.end());
  return names;
}

void WritePrimaryCsv(const std::string& path, int width, int height,
                     const std::vector<PrimarySample>& primary) {
  ZEPHYR_CHECK_EQ(primary.size(), size_t(width) * height);
  OutputFile file(path, "--dump-primary file");
  std::FILE* f = file.Stream();
  std::fprintf(f, "x,y,dx,dy,dz,object,t,flags\n");
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const PrimarySample& s = primary[size_t(y) * width + x];
      const Vec3& d = s.hit.direction;
      std::fprintf(f, "%d,%d,%.17g,%.17g,%.17g,%d,%.17g,%u\n", x, y, d.x, d.y, d.z, s.hit.object,
                   s.hit.object >= 0 ? s.hit.t : 0.0, s.flags);
    }
  }
  file.Commit();
}

void CheckRenderOutputs(const RenderOptions& options) {
  CheckOutputs({{"--out", options.out},
                {"--dump-primary", options.dumpPrimary},
                {"--report", options.report}},
               {{"the scene file", options.scenePath}});
}

namespace {

const RenderMethodEntry& MethodNamed(const std::string& method) {
  auto it = std::find_if(std::begin(kMethods), std::end(kMethods),
                         [&](const RenderMethodEntry& m) { return method == m.name; });
  if (it == std::end(kMethods)) {
    std::string known;
    for (const auto& name : RenderMethodNames()) known += (known.empty() ? "" : ", ") + name;
    throw UserError("--method: unknown method '" + method + "' (known: " + known + ")");
  }
  return *it;
}

}  // namespace

RenderMethodUse RenderMethodUses(const std::string& method) {
  const RenderMethodEntry& m = MethodNamed(method);
  return {.array = m.usesArray, .farm = m.child != nullptr, .wavefront = m.usesWavefront};
}

std::string RenderMethodsUsing(bool array, bool farm) {
  std::string names;
  for (const RenderMethodEntry& m : kMethods)
    if ((!array || m.usesArray) && (!farm || m.child != nullptr))
      names += (names.empty() ? "" : ", ") + std::string(m.name);
  return names;
}

namespace {

// What the render is priced on, as the testbed room checks it (before any work, on every
// rank of a farmed render: before its children serve frames).
testbed::PricingRequest PricingRequestOf(const RenderOptions& options,
                                         const RenderMethodEntry& method) {
  return {.testbed = options.testbed,
          .alsoTestbeds = options.alsoTestbeds,
          .method = options.method,
          .farmed = method.child != nullptr,
          .usesArray = method.usesArray,
          .arrayProfile = options.simd.profile};
}

// Every output and option checked before the scene is read: nothing is computed for an
// output that could not be written.
void CheckRenderRequest(const RenderOptions& options, const RenderMethodEntry& method) {
  CheckRenderOutputs(options);
  if (method.check) method.check(options);
}

// The scene, its warnings printed, checked against the memory the method needs for it.
Scene ReadSceneFor(const RenderOptions& options, const RenderMethodEntry& method,
                   RenderOutput& out) {
  Scene scene;
  {
    PhaseTimer timer(out.phases, "readScene");
    scene = ReadNffFile(options.scenePath);
  }
  for (const std::string& w : scene.warnings) std::fprintf(stderr, "zephyr: %s\n", w.c_str());
  // What a deep ray tree costs (issue 39: `--depth 64` through glass ran past a minute): a
  // surface that both reflects and transmits may double the rays at every level.
  if (options.trace.depth > kDeepTreeWarningDepth &&
      std::any_of(scene.materials.begin(), scene.materials.end(),
                  [](const Material& m) { return m.ks > 0 && m.t > 0; }))
    std::fprintf(stderr,
                 "zephyr: warning: --depth %d with a surface that both reflects and transmits: "
                 "each level may double a pixel's rays, up to 2^%d - 1 at worst (docs/shading.md, "
                 "\"Depth\"); the default is 5\n",
                 options.trace.depth, options.trace.depth);
  const Camera& c = scene.camera;
  CheckMemoryFits(
      "render --method " + options.method + " at " + std::to_string(c.width) + "x" +
          std::to_string(c.height),
      {.perPixel =
           method.bytesPerPixel + (options.dumpPrimary.empty() ? 0 : method.dumpBytesPerPixel),
       .pixels = uint64_t(c.width) * uint64_t(c.height)});
  out.scene = {.path = options.scenePath,
               .objects = scene.objects.size(),
               .lights = scene.lights.size(),
               .width = c.width,
               .height = c.height};
  return scene;
}

// --testbed (and --also-testbed): modelled seconds of the counted work.
void Price(const RenderOptions& options, const Scene& scene, RenderOutput& out) {
  testbed::CountedWork work;
  if (out.hostWork) work.host = &*out.hostWork;
  bitserial::CycleReport everyBounce;  // array: the primary pass's and the wavefront's
  if (out.simd) {
    work.arrayCycles = &out.simd->array.cycles;
    if (out.wavefront) {
      everyBounce.Add(out.simd->array.cycles);
      everyBounce.Add(out.wavefront->cycles);
      work.arrayCycles = &everyBounce;
    }
    if (out.simd->refine) work.refineCycles = &out.simd->refine->array.cycles;
    work.recomputedPixels = uint64_t(out.simd->recomputedPixels);
    work.recomputeWork = &out.simd->recomputeWork;
  }
  testbed::FarmTimes farmTimes;
  if (out.farm) {
    farmTimes = farmed::FarmTimesOf(*out.farm);
    work.farm = &farmTimes;
  }
  out.testbed = testbed::ModelTime(options.testbed, work, scene);
  for (const std::string& bed : options.alsoTestbeds)
    out.alsoTestbeds.push_back(*testbed::ModelTime(bed, work, scene));
}

// The image, the primary hits and the report; a farm's checkpoint removed only once every
// output is on disk (kept, and named, when one cannot be written).
void WriteOutputs(const RenderOptions& options, RenderOutput& out) {
  const int width = out.image.width, height = out.image.height;
  try {
    if (!options.out.empty()) {
      PhaseTimer timer(out.phases, "writePng");
      WritePng(options.out, out.image);
    }
    if (!options.dumpPrimary.empty()) {
      if (out.primary.size() != size_t(width) * height)
        throw UserError("--dump-primary: method '" + options.method +
                        "' does not produce primary hits");
      PhaseTimer timer(out.phases, "dumpPrimary");
      WritePrimaryCsv(options.dumpPrimary, width, height, out.primary);
    }
    if (!options.report.empty())
      WriteOutputFile(options.report, "report", RenderReportJson(out).dump(2) + "\n");
  } catch (const UserError& e) {
    if (out.removeWhenWritten.empty()) throw;
    // The rendered frames are still on disk: say so, and how to finish without re-rendering.
    std::string kept;
    for (const std::string& path : out.removeWhenWritten) kept += (kept.empty() ? "" : ", ") + path;
    throw UserError(std::string(e.what()) + "; every rendered frame is kept in " + kept +
                    " — rerun with --resume to write the outputs without rendering them again");
  }
  // Only now, with every output on disk, is the checkpoint no longer needed.
  for (const std::string& path : out.removeWhenWritten) std::remove(path.c_str());
}

}  // namespace

RenderOutput RunRender(const RenderOptions& given) {
  RenderOptions options = given;
  options.simd.hostAccel = options.trace.accel;  // the pass's recompute traces on the host too
  const RenderMethodEntry& method = MethodNamed(options.method);
  if (method.usesArray) simd::ResolveMachine(options.simd);  // once (the command did already)
  testbed::CheckPricingRequest(PricingRequestOf(options, method));
  if (method.child) method.child(options);  // a child rank serves frames and ends there
  CheckRenderRequest(options, method);
  RenderOutput out;
  out.method = options.method;
  out.trace = options.trace;
  const Scene scene = ReadSceneFor(options, method, out);
  {
    PhaseTimer timer(out.phases, "render");
    method.render(scene, options, out);
  }
  ZEPHYR_CHECK(out.image.width == scene.camera.width && out.image.height == scene.camera.height);
  Price(options, scene, out);
  WriteOutputs(options, out);
  return out;
}

}  // namespace zephyr
