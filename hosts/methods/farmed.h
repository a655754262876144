// hosts/methods/farmed.h — what dist and hetero share on top of the frame farm
// (hosts/farm/farm.h): the set-up message every child gets (the scene as exact NFF and the
// tracing options), the farm's options from RenderOptions, pixels as bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hosts/farm/farm.h"
#include "hosts/methods/output.h"
#include "hosts/testbed/testbed.h"

namespace zephyr::farmed {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "pixels travel as 3 doubles");
inline constexpr std::size_t kPixelBytes = sizeof(Vec3);  // linear RGB, 3 doubles

// The set-up text for `method`: {"method", "scene" (NFF), "depth", "precision",
// "sphereTest", "accel"} plus `more` (hetero: "dirFracBits", "refineDirFracBits").
std::string SetupText(const std::string& method, const Scene& scene, const TraceOptions& trace,
                      const nlohmann::json& more = nlohmann::json::object());

// A child's reading of the set-up text. UserError ("malformed set-up message: …") when it is
// not JSON, misses a field, or was made for another method than `method`.
struct ChildSetup {
  nlohmann::json json;  // everything, for the method's own fields
  Scene scene;
  TraceOptions trace;
};
ChildSetup ReadSetup(const std::string& text, const std::string& method);

// UserError for a bad --frame, --in-flight or --child-timeout (checked on every rank before
// MPI starts, so each reports it).
void CheckDistOptions(const DistOptions& options);
// The farm's options: the checkpoint beside --out, --resume, the timeout, frames in flight.
FramedOptions FarmOptions(const RenderOptions& options);

// A child has served its frames and has nothing to write: end the process here (MPI is
// finalized by the at-exit hook, or here under SimGrid), before the render command would
// write outputs.
[[noreturn]] void EndChild();

// A child's trace counters summed over its frames, and under the simulated testbed the
// host work each frame charges to the child's simulated host (testbed::ChargeHostWork).
// Json() is the "work" section of the child's stats message (docs/distributed.md); under
// simulation it adds "testbed": host, busySeconds (charged), idleSeconds, clockAtStats.
class ChildStats {
 public:
  void AddFrame(const TraceStats& frame);
  nlohmann::json Json() const;

 private:
  TraceStats stats_;
  double chargedSeconds_ = 0;  // simulated seconds (0 outside the simulated build)
};

// The render command's check of the farm's options before any work (dist and hetero):
// --frame, --in-flight, --child-timeout; --resume needs --out and an existing checkpoint
// OUT.frames, which must be a regular file and no other input or output. UserError.
void CheckFarmOptions(const RenderOptions& options);

// The parent's own host work under the simulated testbed (docs/testbed.md): `pixels` pixels
// handled (a frame's slice packed, or its result pasted into the image), charged as that many
// "pixel" events of the work table to the parent's simulated host. Nothing outside it.
void ChargeParentPixels(std::uint64_t pixels);

// What the testbed needs of a finished farm (testbed::FarmTimes): per child its rank, host
// and, under simulation, the busy seconds its stats message's "work" (ChildStats::Json) gave.
// UserError for a malformed "work" section (it came from a child over MPI).
testbed::FarmTimes FarmTimesOf(const FarmReport& report);

// The farm's image bytes (kPixelBytes a pixel, row-major) as an Image.
Image ToImage(const std::vector<std::byte>& bytes, int width, int height);

}  // namespace zephyr::farmed
