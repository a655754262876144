// hosts/methods/render.h — the runner: rendering a scene file with one of the five methods
// (seq, simd, array, dist, hetero; docs/background.md, "The four methods", and
// docs/wavefront.md for the fifth), and the table of methods.
//
// A method is a function that fills a RenderOutput from a scene and the options (both typed,
// hosts/methods/output.h). The table (hosts/methods/render.cpp) names each method once; each
// method's code is in its own file (seq.cpp, simd.cpp, array.cpp, dist.cpp, hetero.cpp).
#pragma once

#include <string>
#include <vector>

#include "hosts/methods/output.h"

namespace zephyr {

// The registered method names, sorted (array, dist, hetero, seq, simd).
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
