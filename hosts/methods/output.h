// hosts/methods/output.h — what every method takes and fills: the typed options of a render
// (those every method shares, then one struct per family of methods: the SIMD pass's, the
// frame farm's, the wavefront's) and its typed output, RenderOutput, kept typed until the
// report is written (hosts/methods/report.h). The runner and the table of methods that use
// them are hosts/methods/render.h; the command line that fills them, hosts/cmd/render.cpp.
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

}  // namespace zephyr
