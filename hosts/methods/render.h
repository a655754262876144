// hosts/methods/render.h — rendering a scene file with one of the four methods, and the table
// of methods (seq, simd, dist, hetero; docs/background.md, "The four methods").
//
// A method is a function that fills a RenderOutput from a scene and the options. The table
// (hosts/methods/render.cpp) names each method once; each method's code is in its own file
// (seq.cpp, simd.cpp, dist.cpp, hetero.cpp). Options are typed: those every method shares,
// then one struct per family of methods (the SIMD pass's, the frame farm's). The command
// line that fills them is hosts/cmd/render.cpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hosts/farm/farm.h"
#include "hosts/methods/phases.h"
#include "hosts/scene/scene.h"
#include "hosts/simd/pass.h"
#include "hosts/testbed/testbed.h"
#include "hosts/trace/image.h"
#include "hosts/trace/tracer.h"
#include "hosts/wavefront/wavefront.h"

namespace zephyr {

// The options of dist and hetero (the frame farm; docs/distributed.md).
// The flags' ranges (checked as the command line is parsed, hosts/cmd/flags.h): a frame
// is at most an image's side (kMaxResolution), a child holds at most kMaxFramesInFlight.
inline constexpr int kMaxFramesInFlight = 1024;
inline constexpr double kMinChildTimeoutSeconds =
    1e-3;  // --child-timeout must be > 0: 1 ms at least

struct DistOptions {
  int frameSize = 64;   // --frame: F×F frames (UserError if < 1)
  bool resume = false;  // --resume: render only the frames missing from OUT.frames
  double childTimeoutSeconds =
      60;                  // --child-timeout: a silent child holding frames is lost (> 0 s)
  int framesInFlight = 2;  // --in-flight: frames handed to a child before it answers
};

struct RenderOptions {
  std::string method = "seq";
  std::string scenePath;
  std::string out;          // PNG path ("" = none)
  std::string report;       // JSON report path ("" = none)
  std::string dumpPrimary;  // CSV of primary hits ("" = none)
  TraceOptions trace;       // depth, precision, sphere test (every method shades on the host)
  bool progress = true;     // progress bar when stderr is a terminal
  simd::SimdOptions simd;   // simd and hetero: formats, uncertain pixels, machine profile
  DistOptions dist;         // dist and hetero
  wavefront::WavefrontOptions wavefront;  // array: the compaction and the secondary formats
  // --testbed: the modelled system whose seconds the report gives ("" = none; the names are
  // testbed::TestbedNames(), docs/testbed.md). UserError for an unknown name.
  std::string testbed;
  // --also-testbed: more testbeds the same counted work is priced on (seq, simd, array: one
  // process, no SimGrid), each a separate ModelledTime; with an array, each must have the
  // array's profile. Needs `testbed`. UserError for a farmed method or a mismatch.
  std::vector<std::string> alsoTestbeds;
};

// One primary-ray record per pixel for --dump-primary; `flags` is method-specific (0 = plain
// hit/miss; the SIMD method sets bits for detected fixed-point failures).
struct PrimarySample {
  PrimaryHit hit;
  uint32_t flags = 0;
};

// What a render made, typed until the report is written (RenderReportJson,
// hosts/methods/report.h: the one place the report's schema lives).
struct RenderOutput {
  Image image;
  std::vector<PrimarySample> primary;  // filled when options.dumpPrimary is set, row-major
  std::string method;
  struct SceneFacts {
    std::string path;
    std::size_t objects = 0, lights = 0;
    int width = 0, height = 0;
  } scene;
  TraceOptions trace;
  Phases phases;                       // wall seconds per phase
  std::optional<TraceStats> hostWork;  // seq, simd: the host's counted work
  // simd, array, hetero: the primary pass (its matrix emptied once the image and dump have it).
  std::optional<simd::PrimaryPass> simd;
  std::optional<FarmReport> farm;                       // dist, hetero: the frame farm's figures
  std::optional<wavefront::WavefrontResult> wavefront;  // array: every bounce on the array
  std::optional<testbed::ModelledTime> testbed;         // --testbed: modelled seconds
  std::vector<testbed::ModelledTime> alsoTestbeds;      // --also-testbed, in the order given
  // Files deleted once every output is written (dist/hetero's frame checkpoint); kept when
  // a write fails, so --resume can finish the job.
  std::vector<std::string> removeWhenWritten;
};

// The registered method names, sorted (dist, hetero, seq, simd).
std::vector<std::string> RenderMethodNames();

// What a method uses beyond the shared options, for the command line to refuse a flag the
// method would ignore: the SIMD pass on the array (its formats, --uncertain, --machine,
// --threads), the frame farm under mpirun (--frame, --resume, --child-timeout, --in-flight).
struct RenderMethodUse {
  bool array = false, farm = false;
  bool wavefront = false;  // the secondary rays on the array (--compact, --array-frac-bits)
};
// UserError for an unknown method (listing the known ones).
RenderMethodUse RenderMethodUses(const std::string& method);
// The methods that use the array, or the farm, for messages ("simd, hetero").
std::string RenderMethodsUsing(bool array, bool farm);

// Checks every output path and the method's options (CheckRenderOutputs, then the method's
// own check), reads the scene and runs the method, then writes --out, --dump-primary and
// --report, each atomically, and only then deletes RenderOutput::removeWhenWritten.
// Returns the output too (tests use it). UserError for an unknown method, a bad scene or an
// unwritable output. A method that runs under MPI (dist, hetero) serves frames in its child
// processes before any scene is read and ends them there: this returns only on the parent.
RenderOutput RunRender(const RenderOptions& options);

// Refuses, before any work: an output path that cannot be written (CheckOutputPath), an
// output that is the scene file, two outputs naming the same file. UserError.
void CheckRenderOutputs(const RenderOptions& options);

// Writes the --dump-primary CSV: header `x,y,dx,dy,dz,object,t,flags`, one row per pixel.
void WritePrimaryCsv(const std::string& path, int width, int height,
                     const std::vector<PrimarySample>& primary);

}  // namespace zephyr
