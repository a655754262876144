// hosts/methods/render.h — the `render` command and the table of methods it dispatches to.
//
// A method is a function that fills a RenderOutput from a scene and the shared options.
// Each method registers itself beside its own code with a file-scope RenderMethodRegistration
// (seq in hosts/methods/seq.cpp, simd in hosts/methods/simd.cpp, dist and hetero in
// hosts/methods/dist_hetero.cpp), so a new method is one entry in one new file; the command itself
// knows no method.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hosts/trace/image.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/tracer.h"

namespace CLI { class App; }

namespace zephyr {

// Options every method shares (flags of `zephyr render`). Method-specific flags belong to
// the method (e.g. read from `extra`, filled by options the method adds to the command).
struct RenderOptions {
  std::string method = "seq";
  std::string scenePath;
  std::string out;          // PNG path ("" = none)
  std::string report;       // JSON report path ("" = none)
  std::string dumpPrimary;  // CSV of primary hits ("" = none)
  TraceOptions trace;       // depth, precision, sphere test
  bool progress = true;     // progress bar when stderr is a terminal
  std::map<std::string, std::string> extra;  // method-specific flags, by flag name
};

// One primary-ray record per pixel for --dump-primary; `flags` is method-specific (0 = plain
// hit/miss; the SIMD method sets bits for detected fixed-point failures).
struct PrimarySample {
  PrimaryHit hit;
  uint32_t flags = 0;
};

struct RenderOutput {
  Image image;
  std::vector<PrimarySample> primary;  // filled when options.dumpPrimary is set, row-major
  nlohmann::json report;               // the method adds "phases", counters, its own sections
  // Files deleted once every output is written (dist/hetero's frame checkpoint); kept when
  // a write fails, so --resume can finish the job.
  std::vector<std::string> removeWhenWritten;
};

using RenderMethod =
    std::function<void(const Scene& scene, const RenderOptions& options, RenderOutput& out)>;

// Runs before the scene is read. A method whose process may be a helper of another (an MPI
// child of dist/hetero) serves there and returns true: RunRender then reads no scene file —
// on a cluster the file exists only where the parent runs — and writes no outputs.
using RenderServeInstead = std::function<bool(const RenderOptions& options)>;

// Runs on the process that writes the outputs, after RunRender's own checks of the output
// paths and before the scene is read or any work starts: the method's check of its own
// flags and of what it cannot do with the shared ones (e.g. dist has no --dump-primary, its
// checkpoint must not be another output). Throws UserError.
using RenderCheckOptions = std::function<void(const RenderOptions& options)>;

struct RenderMethodRegistration {
  RenderMethodRegistration(std::string name, std::string description, RenderMethod method,
                           RenderServeInstead serveInstead = nullptr,
                           RenderCheckOptions checkOptions = nullptr);
};

// A method's own flags: `add` puts options on the render command, storing their values in
// options.extra (e.g. hosts/methods/simd.cpp adds --frac-bits).
struct RenderFlagRegistration {
  explicit RenderFlagRegistration(std::function<void(CLI::App& command, RenderOptions& options)> add);
};

// The registered method names, sorted.
std::vector<std::string> RenderMethodNames();

// Checks every output path and the method's flags (CheckRenderOutputs, then the method's
// RenderCheckOptions), reads the scene and runs the method, then writes --out, --dump-primary
// and --report, each atomically, and only then deletes RenderOutput::removeWhenWritten.
// Returns the output too (tests use it).
RenderOutput RunRender(const RenderOptions& options);

// Refuses, before any work: an output path that cannot be written (CheckOutputPath), an
// output that is the scene file, two outputs naming the same file. UserError.
void CheckRenderOutputs(const RenderOptions& options);

// Writes the --dump-primary CSV: header `x,y,dx,dy,dz,object,t,flags`, one row per pixel.
void WritePrimaryCsv(const std::string& path, int width, int height,
                     const std::vector<PrimarySample>& primary);

}  // namespace zephyr
