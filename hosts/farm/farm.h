// hosts/farm/farm.h — the frame farm shared by the distributed and heterogeneous methods
// (paper §4; docs/distributed.md): rank 0 (the parent) cuts the image into frames and hands them out on
// demand; ranks 1..K (the children) receive the job once, then render frame after frame.
//
// What a child computes is a FrameWork: "given a frame rectangle (and, for hetero, the
// frame's slice of the per-pixel matrix), produce its pixels". The farm does not know what a
// pixel is — it moves bytes — so dist (whole tracing in the child), hetero (secondary rays
// from the parent's SIMD primary pass) and the `mpi-check` test pattern share it.
//
//   std::optional<FramedResult> r = RunFramedMethod("dist", factory, buildJob, options);
//   if (!r) return;  // a child: it served frames and has no output of its own
//   ... write r->image and r->report ...
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hosts/farm/frame.h"
#include "hosts/farm/session.h"

namespace zephyr {

class FrameWork {
 public:
  virtual ~FrameWork() = default;
  virtual int ImageWidth() const = 0;
  virtual int ImageHeight() const = 0;
  virtual std::size_t BytesPerPixel() const = 0;
  // Bytes per pixel of the slice a kWork message carries (0 for dist).
  virtual std::size_t SliceBytesPerPixel() const { return 0; }
  // Writes frame.PixelCount() × BytesPerPixel() bytes, rows top to bottom. `slice` holds
  // frame.PixelCount() × SliceBytesPerPixel() bytes in the same order.
  virtual void RenderFrame(const Frame& frame, std::span<const std::byte> slice,
                           std::span<std::byte> pixels) = 0;
  // The work's own counters (e.g. rays traced), sent to the parent in the stats message and
  // reported per child as "work".
  virtual nlohmann::json Stats() const { return nlohmann::json::object(); }
};

// Builds a child's FrameWork from the job's set-up text (throws UserError when it cannot).
using FrameWorkFactory = std::function<std::unique_ptr<FrameWork>(const std::string& setup)>;

// The parent's view of a job.
struct FramedJob {
  std::string method;  // for messages and the report
  int imageWidth = 0, imageHeight = 0, frameSize = 0;
  std::size_t bytesPerPixel = 0;
  std::string setup;  // sent once to every child (e.g. the scene text and the options)
  // Hetero only (unset for dist): the frame's slice of the per-pixel matrix, or nullopt when
  // no primary ray of the frame hit anything — such a degenerate frame is filled by
  // fillDegenerate at the parent and costs no message.
  std::function<std::optional<std::vector<std::byte>>(const Frame&)> sliceFor;
  std::function<void(const Frame&, std::span<std::byte>)> fillDegenerate;
  double parentPassSeconds = 0;  // hetero: the SIMD primary pass, timed by the caller
};

struct FramedOptions {
  std::string checkpointPath;       // "" = no checkpoint
  bool resume = false;              // render only the frames missing from the checkpoint
  double childTimeoutSeconds = 60;  // a child holding a frame this long without answering is lost
  int framesInFlight = 2;           // frames handed to a child before it returns one
};

struct FramedResult {
  std::vector<std::byte> image;  // imageWidth × imageHeight × bytesPerPixel, row-major
  nlohmann::json report;         // see docs/distributed.md, "Accounting"
  // The checkpoint holding every frame ("" = none). It is left on disk: the caller deletes
  // it (RemoveCheckpoint) only once its outputs are safely written.
  std::string checkpointPath;
};

// The whole method: starts MPI (≥ 2 ranks or UserError); on a child serves frames and
// returns nullopt; on the parent builds the job (only there: children never read the scene)
// and renders it. After a UserError on the parent the children are still released (at exit)
// so the job ends.
std::optional<FramedResult> RunFramedMethod(const std::string& method,
                                            const FrameWorkFactory& factory,
                                            const std::function<FramedJob()>& buildJob,
                                            const FramedOptions& options);

// The pieces RunFramedMethod is made of.
// Starts MPI and checks there is a parent and at least one child.
MpiSession& StartFramedMethod(const std::string& method);
// The child loop (ranks ≥ 1): returns when the parent says stop, or after reporting a failure.
void ServeFrames(const FrameWorkFactory& factory);
// The parent (rank 0). Throws UserError when the job cannot finish (all children lost,
// a malformed message, a child's failure, a checkpoint that cannot be written); finished
// frames stay in the checkpoint, which is never deleted here.
FramedResult RenderFrames(const FramedJob& job, const FramedOptions& options);

}  // namespace zephyr
