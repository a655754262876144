// hosts/methods/dist.cpp — the distributed method (paper §4; docs/distributed.md) on the frame
// farm of hosts/farm/farm.h: children trace whole frames with the sequential tracer
// (RenderRegion), so the image is bit-identical to --method seq.
//
// Needs `mpirun -np K+1`: rank 0 is the parent, which alone reads the scene and writes the
// outputs; a child serves frames and then ends its process (it has no output of its own).
#include <cstring>
#include <memory>

#include "fixed/check.h"
#include "hosts/methods/farmed.h"
#include "hosts/methods/methods.h"
#include "hosts/testbed/simulation.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {
namespace {

using farmed::kPixelBytes;

// A dist child's work: trace each frame's pixels whole.
class DistWork : public FrameWork {
 public:
  explicit DistWork(const std::string& setupText) {
    farmed::ChildSetup setup = farmed::ReadSetup(setupText, "dist");
    scene_ = std::move(setup.scene);
    tracer_ = Tracer::Create(scene_, setup.trace);
    stats_.AddFrame(tracer_->BuildWork());  // each child builds (and is charged) its own BVH
  }
  int ImageWidth() const override { return scene_.camera.width; }
  int ImageHeight() const override { return scene_.camera.height; }
  std::size_t BytesPerPixel() const override { return kPixelBytes; }
  void RenderFrame(const Frame& f, std::span<const std::byte>,
                   std::span<std::byte> pixels) override {
    TraceStats frameStats;
    RenderRegion(*tracer_, f.x0, f.y0, f.width, f.height, block_, frameStats);
    stats_.AddFrame(frameStats);
    ZEPHYR_CHECK_EQ(block_.size() * kPixelBytes, pixels.size());
    std::memcpy(pixels.data(), block_.data(), pixels.size());
  }
  nlohmann::json Stats() const override { return stats_.Json(); }

 private:
  Scene scene_;
  std::unique_ptr<Tracer> tracer_;
  std::vector<Vec3> block_;
  farmed::ChildStats stats_;
};

}  // namespace

void DistChildEntry(const RenderOptions& options) {
  farmed::CheckDistOptions(options.dist);
  if (ServeIfChild("dist",
                   [](const std::string& setup) { return std::make_unique<DistWork>(setup); }))
    farmed::EndChild();
}

void RenderDist(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  FrameGrid(c.width, c.height, options.dist.frameSize);  // a bad frame size: before any message
  testbed::StartLinkAccounting();                        // simulated testbed only
  FramedJob job;
  job.method = "dist";
  job.imageWidth = c.width, job.imageHeight = c.height, job.frameSize = options.dist.frameSize;
  job.bytesPerPixel = kPixelBytes;
  job.setup = farmed::SetupText("dist", scene, options.trace);
  job.pasted = [](const Frame& f) { farmed::ChargeParentPixels(f.PixelCount()); };
  FramedResult result = RenderFrames(job, farmed::FarmOptions(options));
  out.image = farmed::ToImage(result.image, c.width, c.height);
  out.farm = std::move(result.report);
  if (!result.checkpointPath.empty()) out.removeWhenWritten.push_back(result.checkpointPath);
}

void CheckDistOptions(const RenderOptions& o) {
  farmed::CheckFarmOptions(o);
  if (!o.dumpPrimary.empty())
    throw UserError(
        "--dump-primary: --method dist has no primary hits at the parent (its "
        "children trace whole frames); --method seq gives the same image and dumps them");
}

}  // namespace zephyr
