// hosts/methods/dist_hetero.cpp — the distributed and heterogeneous methods as render methods
// (paper §4; docs/distributed.md), built on the frame farm of hosts/farm/farm.h.
//
//   dist:   children trace whole frames with the sequential tracer (RenderRegion), so the
//           image is bit-identical to --method seq.
//   hetero: the parent runs the SIMD primary pass on the emulated array; children shade
//           frames from their slice of the per-pixel matrix (simd::ShadeRegion), so the image
//           is bit-identical to --method simd. The slice carries 13 bytes a pixel (object,
//           flags, t; hosts/methods/hetero_entry.h); the child recomputes each direction. Frames
//           where no primary ray hit anything are filled with the background at the parent
//           and cost no message.
//
// Both need `mpirun -np K+1`: rank 0 is the parent, which alone writes the outputs; a child
// serves frames and then ends its process (it has no output of its own).
#include "hosts/methods/hetero_entry.h"

#include <CLI/CLI.hpp>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "fixed/check.h"
#include "hosts/farm/farm.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"
#include "hosts/methods/render.h"
#include "hosts/methods/phases.h"
#include "hosts/simd/pass.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {
namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "pixels travel as 3 doubles");
constexpr std::size_t kPixelBytes = sizeof(Vec3);

}  // namespace

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
      simd::kOverflow | simd::kGrazing | simd::kNearTie | simd::kRecomputed;
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

Vec3 MatrixDirection(const PrimaryRays& rays, int x, int y, int dirFracBits, std::uint32_t flags) {
  const Vec3 exact = rays.At(x, y).direction;
  if (flags & simd::kRecomputed) return exact;
  auto quantised = [&](double c) {
    return std::ldexp(double(std::int64_t(std::llround(std::ldexp(c, dirFracBits)))), -dirFracBits);
  };
  return Normalize(Vec3{quantised(exact.x), quantised(exact.y), quantised(exact.z)});
}

}  // namespace hetero

namespace {

using hetero::kEntryBytes;

// What every child needs, sent once: the scene (as exact NFF) and the tracing options;
// hetero adds the direction fraction bits of the SIMD pass (to recompute the directions).
std::string SetupText(const std::string& method, const Scene& scene, const TraceOptions& t,
                      int dirFracBits = -1) {
  nlohmann::json j = {{"method", method},
                      {"scene", WriteNff(scene)},
                      {"depth", t.depth},
                      {"precision", PrecisionName(t.precision)},
                      {"sphereTest", SphereTestName(t.sphereTest)}};
  if (dirFracBits >= 0) j["dirFracBits"] = dirFracBits;
  return j.dump();
}

class TracerWork : public FrameWork {
 public:
  explicit TracerWork(const std::string& setupText) {
    try {
      auto j = nlohmann::json::parse(setupText);
      method_ = j.at("method").get<std::string>();
      scene_ = ParseNffOrThrow(j.at("scene").get<std::string>(), "<scene from the parent>");
      options_.depth = j.at("depth").get<int>();
      options_.precision = ParsePrecision(j.at("precision").get<std::string>());
      options_.sphereTest = ParseSphereTest(j.at("sphereTest").get<std::string>());
      if (j.at("method") == "hetero") dirFracBits_ = j.at("dirFracBits").get<int>();
    } catch (const nlohmann::json::exception& e) {
      throw UserError(std::string("malformed set-up message: ") + e.what());
    }
    if (method_ != "dist" && method_ != "hetero")
      throw UserError("malformed set-up message: unknown method '" + method_ + "'");
    if (method_ == "hetero" && (dirFracBits_ < 0 || dirFracBits_ > 60))
      throw UserError("malformed set-up message: dirFracBits " + std::to_string(dirFracBits_));
    tracer_ = Tracer::Create(scene_, options_);
  }
  int ImageWidth() const override { return scene_.camera.width; }
  int ImageHeight() const override { return scene_.camera.height; }
  std::size_t BytesPerPixel() const override { return kPixelBytes; }
  std::size_t SliceBytesPerPixel() const override {
    return method_ == "hetero" ? kEntryBytes : 0;
  }
  void RenderFrame(const Frame& f, std::span<const std::byte> slice,
                   std::span<std::byte> pixels) override {
    TraceStats frameStats;
    if (method_ == "dist") {
      RenderRegion(*tracer_, f.x0, f.y0, f.width, f.height, block_, frameStats);
    } else {
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
          m.hits[i] = hetero::GetEntry(&slice[i * kEntryBytes], int(scene_.objects.size()), m.flags[i]);
          m.hits[i].direction = hetero::MatrixDirection(tracer_->Rays(), x, y, dirFracBits_, m.flags[i]);
        }
      simd::ShadeRegion(*tracer_, m, 0, 0, f.width, f.height, block_, frameStats);
    }
    stats_.Add(frameStats);
    chargedSeconds_ += testbed::ChargeHostWork(frameStats);  // simulated testbed only
    ZEPHYR_CHECK_EQ(block_.size() * kPixelBytes, pixels.size());
    std::memcpy(pixels.data(), block_.data(), pixels.size());
  }
  nlohmann::json Stats() const override {
    nlohmann::json j = stats_.ToJson();
    if (testbed::Simulated()) {
      // Simulated time of this child: charged work is busy, the rest waiting on the network
      // and the parent.
      const double now = testbed::SimulatedNow();
      j["testbed"] = testbed::SimulatedHost();
      j["testbed"]["busySeconds"] = chargedSeconds_;
      j["testbed"]["idleSeconds"] = now - chargedSeconds_;
      j["testbed"]["clockAtStats"] = now;
    }
    return j;
  }

 private:
  std::string method_;
  int dirFracBits_ = -1;
  Scene scene_;
  TraceOptions options_;
  std::unique_ptr<Tracer> tracer_;
  std::vector<Vec3> block_;
  TraceStats stats_;
  double chargedSeconds_ = 0;
};

double DoubleFlag(const RenderOptions& o, const std::string& name, double fallback) {
  auto it = o.extra.find(name);
  if (it == o.extra.end() || it->second.empty()) return fallback;
  try {
    std::size_t used = 0;
    const double v = std::stod(it->second, &used);
    if (used == it->second.size()) return v;
  } catch (const std::exception&) {
  }
  throw UserError("--" + name + ": expected a number, got '" + it->second + "'");
}

FramedOptions FarmOptions(const RenderOptions& o) {
  FramedOptions f;
  f.checkpointPath = o.out.empty() ? "" : CheckpointPathFor(o.out);
  f.resume = o.extra.count("resume") && o.extra.at("resume") == "true";
  f.childTimeoutSeconds = DoubleFlag(o, "child-timeout", 60);
  // Under SimGrid wall-clock time means nothing to the simulated run: no timeout.
  if (testbed::Simulated()) f.childTimeoutSeconds = std::numeric_limits<double>::infinity();
  f.framesInFlight = int(DoubleFlag(o, "in-flight", 2));
  if (f.framesInFlight < 1 || double(f.framesInFlight) != DoubleFlag(o, "in-flight", 2))
    throw UserError("--in-flight: expected a whole number ≥ 1");
  return f;
}

int FrameSize(const RenderOptions& o) {
  const double f = DoubleFlag(o, "frame", 64);
  if (f != double(int(f)) || f < 1)
    throw UserError("--frame: the frame size must be a whole number of pixels ≥ 1, got '" +
                    o.extra.at("frame") + "'");
  return int(f);
}

// A child has served its frames and has nothing to write: end the process here (MPI is
// finalized by the at-exit hook), before the render command would write outputs.
[[noreturn]] void EndChild() {
  if (testbed::Simulated()) FinalizeMpiAtExit();  // no at-exit hook under SMPI (session.cpp)
  std::fflush(stdout);
  std::exit(0);
}

void CopyImage(std::vector<std::byte>& bytes, Image& image) {
  ZEPHYR_CHECK_EQ(bytes.size(), image.pixels.size() * kPixelBytes);
  std::memcpy(image.pixels.data(), bytes.data(), bytes.size());
}

void RenderDist(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  const int frameSize = FrameSize(options);
  FrameGrid(c.width, c.height, frameSize);  // a bad frame size is an error before MPI starts
  auto result = RunFramedMethod(
      "dist", [](const std::string& setup) { return std::make_unique<TracerWork>(setup); },
      [&] {
        FramedJob job;
        job.method = "dist";
        job.imageWidth = c.width, job.imageHeight = c.height, job.frameSize = frameSize;
        job.bytesPerPixel = kPixelBytes;
        job.setup = SetupText("dist", scene, options.trace);
        return job;
      },
      FarmOptions(options));
  if (!result) EndChild();
  out.image = Image(c.width, c.height);
  CopyImage(result->image, out.image);
  out.report["distributed"] = result->report;
  if (!result->checkpointPath.empty()) out.removeWhenWritten.push_back(result->checkpointPath);
}

void RenderHetero(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  const int frameSize = FrameSize(options);
  FrameGrid(c.width, c.height, frameSize);
  simd::PrimaryPass pass;
  std::unique_ptr<Tracer> tracer;
  auto result = RunFramedMethod(
      "hetero", [](const std::string& setup) { return std::make_unique<TracerWork>(setup); },
      [&] {
        FramedJob job;
        job.method = "hetero";
        job.imageWidth = c.width, job.imageHeight = c.height, job.frameSize = frameSize;
        job.bytesPerPixel = kPixelBytes;
        auto start = std::chrono::steady_clock::now();
        pass = simd::RunPrimaryPass(scene, simd::SimdOptionsFrom(options));
        job.parentPassSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (testbed::Simulated()) job.parentPassSeconds = testbed::ChargeArrayPass(pass, scene);
        job.setup = SetupText("hetero", scene, options.trace, pass.plan.dirFracBits);
        std::fprintf(stderr, "cycle report (SIMD primary pass):\n%s", pass.cycleTable.c_str());
        tracer = Tracer::Create(scene, options.trace);
        job.sliceFor = [&](const Frame& f) -> std::optional<std::vector<std::byte>> {
          std::vector<std::byte> slice(f.PixelCount() * kEntryBytes);
          bool anyHit = false;
          std::size_t i = 0;
          for (int y = f.y0; y < f.y0 + f.height; ++y)
            for (int x = f.x0; x < f.x0 + f.width; ++x, ++i) {
              const std::size_t at = std::size_t(y) * c.width + x;
              const PrimaryHit& hit = pass.matrix.hits[at];
              anyHit |= hit.object >= 0;
              // The child recomputes the direction: it must be the matrix's, bit for bit.
              const Vec3 again = hetero::MatrixDirection(tracer->Rays(), x, y,
                                                         pass.plan.dirFracBits, pass.matrix.flags[at]);
              ZEPHYR_CHECK(std::memcmp(&again, &hit.direction, sizeof(Vec3)) == 0);
              hetero::PutEntry(hit, pass.matrix.flags[at], &slice[i * kEntryBytes]);
            }
          if (!anyHit) return std::nullopt;
          return slice;
        };
        // The background exactly as shading a miss gives it (bit-identical to --method simd).
        job.fillDegenerate = [&](const Frame& f, std::span<std::byte> pixels) {
          TraceStats unused;
          std::vector<Vec3> block;
          simd::ShadeRegion(*tracer, pass.matrix, f.x0, f.y0, f.width, f.height, block, unused);
          std::memcpy(pixels.data(), block.data(), pixels.size());
        };
        return job;
      },
      FarmOptions(options));
  if (!result) EndChild();
  out.image = Image(c.width, c.height);
  CopyImage(result->image, out.image);
  out.report["simd"] = pass.Json();
  out.report["distributed"] = result->report;
  if (!result->checkpointPath.empty()) out.removeWhenWritten.push_back(result->checkpointPath);
  out.primary.clear();  // the parent holds the whole matrix: --dump-primary as for simd
  if (!options.dumpPrimary.empty())
    for (size_t i = 0; i < pass.matrix.hits.size(); ++i)
      out.primary.push_back({pass.matrix.hits[i], pass.matrix.flags[i]});
}

// Before any work (RenderCheckOptions): the farm's flags, and the checkpoint OUT.frames,
// which must be no other input or output; --resume needs it to exist.
void CheckFarmOptions(const RenderOptions& o) {
  FrameSize(o);
  const FramedOptions f = FarmOptions(o);
  if (f.resume && o.out.empty())
    throw UserError("--resume needs --out: the frames it resumes are kept in OUT.frames");
  if (f.checkpointPath.empty()) return;
  for (const auto& [what, path] : {std::pair{"the scene", &o.scenePath},
                                   std::pair{"--report", &o.report},
                                   std::pair{"--dump-primary", &o.dumpPrimary}})
    if (!path->empty() && SameFile(*path, f.checkpointPath))
      throw UserError(std::string(what) + " " + *path + " is the checkpoint of --out " + o.out +
                      " (" + f.checkpointPath + "); choose another name");
  struct stat s;
  const bool exists = ::stat(f.checkpointPath.c_str(), &s) == 0;
  if (exists && !S_ISREG(s.st_mode))
    throw UserError(f.checkpointPath + " (the checkpoint of --out " + o.out +
                    ") exists and is not a regular file");
  if (f.resume && !exists)
    throw UserError("nothing to resume: no checkpoint " + f.checkpointPath +
                    " (it is written by a run with the same --out)");
}

void CheckDistOptions(const RenderOptions& o) {
  CheckFarmOptions(o);
  if (!o.dumpPrimary.empty())
    throw UserError("--dump-primary: --method dist has no primary hits at the parent (its "
                    "children trace whole frames); --method seq gives the same image and dumps them");
}

void CheckHeteroOptions(const RenderOptions& o) {
  CheckFarmOptions(o);
  simd::SimdOptionsFrom(o);  // --frac-bits, --uncertain, ... before the SIMD pass
}

// Before the scene is read: children (ranks >= 1) serve frames from the setup the parent
// sends (the scene as NFF text) and end there, so only the parent needs the scene file.
bool ServeAsChild(const RenderOptions& options) {
  FrameSize(options);  // a bad --frame is reported by every rank before MPI starts
  if (StartFramedMethod(options.method).Rank() == 0) return false;
  ServeFrames([](const std::string& setup) { return std::make_unique<TracerWork>(setup); });
  EndChild();
}

RenderMethodRegistration distReg(
    "dist",
    "distributed: under mpirun, children trace whole F×F frames handed out on demand "
    "(bit-identical to seq)",
    RenderDist, ServeAsChild, CheckDistOptions);
RenderMethodRegistration heteroReg(
    "hetero",
    "heterogeneous: the SIMD primary pass at the parent, children shade the frames with a hit "
    "(under mpirun; bit-identical to simd)",
    RenderHetero, ServeAsChild, CheckHeteroOptions);

RenderFlagRegistration flags([](CLI::App& cmd, RenderOptions& o) {
  cmd.add_option("--frame", o.extra["frame"], "dist/hetero: frame size F (F×F frames; default 64)");
  cmd.add_flag("--resume{true}", o.extra["resume"],
               "dist/hetero: render only the frames missing from OUT.frames (the checkpoint)");
  cmd.add_option("--child-timeout", o.extra["child-timeout"],
                 "dist/hetero: seconds a child may hold frames without answering (default 60)");
  cmd.add_option("--in-flight", o.extra["in-flight"],
                 "dist/hetero: frames handed to a child before it returns one (default 2)");
});

}  // namespace
}  // namespace zephyr
