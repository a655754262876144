// hosts/farm/farm.h — the frame farm shared by the distributed and heterogeneous methods
// (paper §4; docs/distributed.md): rank 0 (the parent) cuts the image into frames and hands them
// out on demand; ranks 1..K (the children) receive the job once, then render frame after frame.
//
// What a child computes is a FrameWork: "given a frame rectangle (and, for hetero, the
// frame's slice of the per-pixel matrix), produce its pixels". The farm does not know what a
// pixel is — it moves bytes — so dist (whole tracing in the child), hetero (secondary rays
// from the parent's SIMD primary pass) and the `mpi-check` test pattern share it.
//
//   if (ServeIfChild("dist", factory)) return;  // a child: served frames, has no output
//   FramedResult r = RenderFrames(job, options);  // the parent
//   ... write r.image and r.report (a FarmReport) ...
//
// Files: farm.h (this interface), child.cpp (the child loop), parent.cpp (the parent: queue,
// losses, checkpoint, report), frame.h (frames and the queue), protocol.h (messages),
// session.h (MPI), checkpoint.h, test_fault.h (the tests' fault injection).
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
#include "hosts/farm/protocol.h"
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
  // Called at the parent after a child's frame is pasted into the image (unset: nothing),
  // e.g. to charge the parent's own work to its simulated host (docs/testbed.md).
  std::function<void(const Frame&)> pasted;
};

struct FramedOptions {
  std::string checkpointPath;       // "" = no checkpoint
  bool resume = false;              // render only the frames missing from the checkpoint
  double childTimeoutSeconds = 60;  // a child holding a frame this long without answering is lost
  int framesInFlight = 2;           // frames handed to a child before it returns one
};

// One child as the parent saw it, and its stats message's figures (docs/distributed.md,
// "Accounting"). Seconds are the child's wall clock (SimGrid's under simulation).
struct ChildReport {
  int rank = 0;
  std::string host;  // from its ready message
  long pid = -1;
  std::uint64_t framesAccepted = 0, pixels = 0;  // results the parent pasted
  std::string lostReason;                        // "" = not lost
  struct Stats {
    int framesRendered = 0;
    double setupSeconds = 0, busySeconds = 0, idleSeconds = 0;
    TrafficAccount sent, received;
    // The FrameWork's own counters (FrameWork::Stats), as the child sent them: the farm
    // knows no pixel; the method that made the work decodes them.
    nlohmann::json work = nlohmann::json::object();
  };
  std::optional<Stats> stats;  // none when no stats message arrived (a lost child)
};

// The parent's figures of a finished job (docs/distributed.md, "Accounting").
struct FarmReport {
  std::string method;
  int ranks = 0, children = 0, frameSize = 0, framesInFlight = 0;
  double childTimeoutSeconds = 0;
  int framesTotal = 0, frameColumns = 0, frameRows = 0, framesSent = 0;
  std::vector<int> skippedFrames;  // degenerate (no primary hit): filled at the parent
  int resumedFrames = 0;           // --resume: frames read back from the checkpoint
  std::vector<int> damagedFrames;  // --resume: frames whose checkpoint records were damaged
  std::vector<int> lostFrames;     // frames handed out again after their child was lost
  TrafficAccount parentToChildren, childrenToParent;
  int ignoredMessages = 0;
  std::vector<ChildReport> perChild;
  double parentPassSeconds = 0;        // FramedJob::parentPassSeconds
  double distributionSeconds = 0;      // wall time handing out and collecting frames
  double parentCpuSeconds = 0;         // the parent's CPU time over it
  double ChildrenBusySeconds() const;  // over the children that sent stats
  double ChildrenIdleSeconds() const;
  // The report's "distributed" section (render --report, mpi-check --report).
  nlohmann::json Json() const;
};

struct FramedResult {
  std::vector<std::byte> image;  // imageWidth × imageHeight × bytesPerPixel, row-major
  FarmReport report;
  // The checkpoint holding every frame ("" = none). It is left on disk: the caller deletes
  // it (RemoveCheckpoint) only once its outputs are safely written.
  std::string checkpointPath;
};

// The one way into a farm child. Starts MPI and checks there is a parent and at least one
// child (UserError naming `method` otherwise). On a child rank (≥ 1) it builds the child's
// FrameWork from the parent's set-up message with `factory`, renders frames until the
// parent says stop (or reports a failure to it) and returns true: the process has no output
// of its own. On the parent (rank 0) it returns false at once.
bool ServeIfChild(const std::string& method, const FrameWorkFactory& factory);

// The parent (rank 0): hands the job's frames out and collects them. UserError when MPI has
// fewer than 2 ranks or the job cannot finish (all children lost, a malformed message, a
// child's failure, a checkpoint that cannot be written); finished frames stay in the
// checkpoint, which is never deleted here (FramedResult::checkpointPath).
FramedResult RenderFrames(const FramedJob& job, const FramedOptions& options);

}  // namespace zephyr
