// hosts/methods/hetero.cpp — the heterogeneous method (paper §4; docs/distributed.md) on the
// frame farm of hosts/farm/farm.h: the parent runs the SIMD primary pass on the emulated
// array; children shade frames from their slice of the per-pixel matrix (simd::ShadeRegion),
// so the image is bit-identical to --method simd. The slice carries 13 bytes a pixel
// (object, flags, t; hosts/methods/hetero_entry.h); the child recomputes each direction.
// Frames where no primary ray hit anything are filled with the background at the parent and
// cost no message.
//
// Needs `mpirun -np K+1`: rank 0 is the parent, which alone reads the scene and writes the
// outputs; a child serves frames and then ends its process.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "fixed/check.h"
#include "hosts/methods/farmed.h"
#include "hosts/methods/hetero_entry.h"
#include "hosts/methods/methods.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/pass.h"
#include "hosts/testbed/simulation.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {

namespace hetero {

void PutEntry(const PrimaryHit& hit, std::uint32_t flags, std::byte* at) {
  ZEPHYR_CHECK_LE(flags, 0xFFu);
  const std::int32_t object = hit.object;
  const std::uint8_t flagByte = std::uint8_t(flags);
  std::memcpy(at, &object, 4);
  std::memcpy(at + 4, &flagByte, 1);
  std::memcpy(at + 5, &hit.t, 8);
}

PrimaryHit GetEntry(const std::byte* at, int objectCount, std::uint32_t& flags) {
  constexpr std::uint32_t kKnown =
      simd::kOverflow | simd::kGrazing | simd::kNearTie | simd::kRecomputed | simd::kRefined;
  std::int32_t object;
  std::uint8_t flagByte;
  PrimaryHit hit;
  std::memcpy(&object, at, 4);
  std::memcpy(&flagByte, at + 4, 1);
  std::memcpy(&hit.t, at + 5, 8);
  if (object < -1 || object >= objectCount)
    throw UserError("malformed work message: matrix names object " + std::to_string(object) +
                    " of a scene with " + std::to_string(objectCount));
  if (flagByte & ~kKnown)
    throw UserError("malformed work message: unknown matrix flag bits " +
                    std::to_string(flagByte & ~kKnown));
  if (!std::isfinite(hit.t) || (object < 0 && hit.t != 0))
    throw UserError("malformed work message: matrix t " + std::to_string(hit.t) +
                    (object < 0 ? " for a miss" : " is not finite"));
  hit.object = object;
  flags = flagByte;
  return hit;
}

Vec3 MatrixDirection(const PrimaryRays& rays, int x, int y, int dirFracBits, int refineDirFracBits,
                     std::uint32_t flags) {
  const Vec3 exact = rays.At(x, y).direction;
  if (flags & simd::kRecomputed) return exact;
  if (flags & simd::kRefined) {
    if (refineDirFracBits < 0)
      throw UserError(
          "malformed work message: a refined pixel, but the set-up named no refine pass");
    return simd::MatrixDirection(exact, refineDirFracBits);
  }
  return simd::MatrixDirection(exact, dirFracBits);
}

}  // namespace hetero

namespace {

using farmed::kPixelBytes;
using hetero::kEntryBytes;

// A hetero child's work: shade each frame from its slice of the matrix.
class HeteroWork : public FrameWork {
 public:
  explicit HeteroWork(const std::string& setupText) {
    farmed::ChildSetup setup = farmed::ReadSetup(setupText, "hetero");
    try {
      dirFracBits_ = setup.json.at("dirFracBits").get<int>();
      refineDirFracBits_ = setup.json.at("refineDirFracBits").get<int>();
    } catch (const nlohmann::json::exception& e) {
      throw UserError(std::string("malformed set-up message: ") + e.what());
    }
    if (dirFracBits_ < 0 || dirFracBits_ > 60)
      throw UserError("malformed set-up message: dirFracBits " + std::to_string(dirFracBits_));
    if (refineDirFracBits_ < -1 || refineDirFracBits_ > 60)
      throw UserError("malformed set-up message: refineDirFracBits " +
                      std::to_string(refineDirFracBits_));
    scene_ = std::move(setup.scene);
    tracer_ = Tracer::Create(scene_, setup.trace);
    stats_.AddFrame(tracer_->BuildWork());  // each child builds (and is charged) its own BVH
  }
  int ImageWidth() const override { return scene_.camera.width; }
  int ImageHeight() const override { return scene_.camera.height; }
  std::size_t BytesPerPixel() const override { return kPixelBytes; }
  std::size_t SliceBytesPerPixel() const override { return kEntryBytes; }
  void RenderFrame(const Frame& f, std::span<const std::byte> slice,
                   std::span<std::byte> pixels) override {
    // The frame's own piece of the matrix, at (0, 0): ShadeRegion's pixels depend only on
    // each pixel's hit, so they equal the full image's. Directions are recomputed from the
    // pixel's place in the image.
    simd::PrimaryMatrix m;
    m.width = f.width, m.height = f.height;
    m.hits.resize(f.PixelCount());
    m.flags.resize(f.PixelCount());
    std::size_t i = 0;
    for (int y = f.y0; y < f.y0 + f.height; ++y)
      for (int x = f.x0; x < f.x0 + f.width; ++x, ++i) {
        m.hits[i] =
            hetero::GetEntry(&slice[i * kEntryBytes], int(scene_.objects.size()), m.flags[i]);
        m.hits[i].direction = hetero::MatrixDirection(tracer_->Rays(), x, y, dirFracBits_,
                                                      refineDirFracBits_, m.flags[i]);
      }
    TraceStats frameStats;
    simd::ShadeRegion(*tracer_, m, 0, 0, f.width, f.height, block_, frameStats);
    stats_.AddFrame(frameStats);
    ZEPHYR_CHECK_EQ(block_.size() * kPixelBytes, pixels.size());
    std::memcpy(pixels.data(), block_.data(), pixels.size());
  }
  nlohmann::json Stats() const override { return stats_.Json(); }

 private:
  int dirFracBits_ = -1;
  int refineDirFracBits_ = -1;  // the refine pass's direction fraction bits; -1: none ran
  Scene scene_;
  std::unique_ptr<Tracer> tracer_;
  std::vector<Vec3> block_;
  farmed::ChildStats stats_;
};

// The frame's slice of the matrix, or nullopt when no primary ray of the frame hit anything.
std::optional<std::vector<std::byte>> Slice(const simd::PrimaryMatrix& matrix, const Frame& f) {
  std::vector<std::byte> slice(f.PixelCount() * kEntryBytes);
  bool anyHit = false;
  std::size_t i = 0;
  for (int y = f.y0; y < f.y0 + f.height; ++y)
    for (int x = f.x0; x < f.x0 + f.width; ++x, ++i) {
      const std::size_t at = std::size_t(y) * matrix.width + x;
      anyHit |= matrix.hits[at].object >= 0;
      hetero::PutEntry(matrix.hits[at], matrix.flags[at], &slice[i * kEntryBytes]);
    }
  if (!anyHit) return std::nullopt;
  return slice;
}

}  // namespace

void HeteroChildEntry(const RenderOptions& options) {
  farmed::CheckDistOptions(options.dist);
  if (ServeIfChild("hetero",
                   [](const std::string& setup) { return std::make_unique<HeteroWork>(setup); }))
    farmed::EndChild();
}

void RenderHetero(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  FrameGrid(c.width, c.height, options.dist.frameSize);
  const auto tracer = Tracer::Create(scene, options.trace);  // its option errors before the pass
  testbed::StartLinkAccounting();  // simulated testbed only (before the matrix crosses SCSI)
  FramedJob job;
  job.method = "hetero";
  job.imageWidth = c.width, job.imageHeight = c.height, job.frameSize = options.dist.frameSize;
  job.bytesPerPixel = kPixelBytes;
  auto start = std::chrono::steady_clock::now();
  simd::PrimaryPass pass = simd::RunPrimaryPass(scene, options.simd);
  job.parentPassSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (testbed::Simulated())
    job.parentPassSeconds = testbed::ChargeArrayCycles(
        pass.array.cycles, pass.refine ? &pass.refine->array.cycles : nullptr,
        testbed::RecomputeWork(pass.recomputeWork), "heterogeneous");
  job.setup =
      farmed::SetupText("hetero", scene, options.trace,
                        {{"dirFracBits", pass.plan.dirFracBits},
                         {"refineDirFracBits", pass.refine ? pass.refine->dirFracBits : -1}});
  // The parent's own work, charged under the simulated testbed: packing each frame's slice,
  // shading the degenerate frames, pasting the children's frames.
  job.sliceFor = [&](const Frame& f) {
    auto slice = Slice(pass.matrix, f);
    if (slice) farmed::ChargeParentPixels(f.PixelCount());
    return slice;
  };
  job.pasted = [](const Frame& f) { farmed::ChargeParentPixels(f.PixelCount()); };
  // The background exactly as shading a miss gives it (bit-identical to --method simd).
  job.fillDegenerate = [&](const Frame& f, std::span<std::byte> pixels) {
    TraceStats work;
    std::vector<Vec3> block;
    simd::ShadeRegion(*tracer, pass.matrix, f.x0, f.y0, f.width, f.height, block, work);
    testbed::ChargeHostWork(work);  // simulated testbed only
    std::memcpy(pixels.data(), block.data(), pixels.size());
  };
  FramedResult result = RenderFrames(job, farmed::FarmOptions(options));
  out.image = farmed::ToImage(result.image, c.width, c.height);
  out.farm = std::move(result.report);
  if (!result.checkpointPath.empty()) out.removeWhenWritten.push_back(result.checkpointPath);
  if (!options.dumpPrimary.empty())  // the parent holds the whole matrix: as for simd
    for (size_t i = 0; i < pass.matrix.hits.size(); ++i)
      out.primary.push_back({pass.matrix.hits[i], pass.matrix.flags[i]});
  pass.matrix = {};  // the image and the dump have it
  out.simd = std::move(pass);
}

void CheckHeteroOptions(const RenderOptions& o) { farmed::CheckFarmOptions(o); }

}  // namespace zephyr
