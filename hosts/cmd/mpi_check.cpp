// `zephyr mpi-check`: the frame farm on a synthetic test pattern, with no scene and no
// tracer — to check an MPI installation (a hostfile, a cluster) and to test the farm itself.
//
// The pattern imitates both methods: `--mode dist` children compute each pixel's "primary
// hit" (the nearest of a few discs) and its colour; `--mode hetero` has the parent compute
// the per-pixel matrix {object, t, direction} and send only frames where some pixel hit a
// disc, children colouring from the matrix. `--local` computes the same image in one process
// without MPI — the reference the farm must reproduce bit for bit. Pixels are 3 floats; the
// output is a PFM (portable float map) image.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/methods/render.h"
#include "hosts/scene/nff.h"
#include "hosts/farm/farm.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/io/output_file.h"

namespace zephyr {
namespace {

struct PatternOptions {
  int width = 48, height = 32, objects = 3, work = 1;
  std::uint32_t seed = 1;
  std::string mode = "dist";
};

struct Disc {
  float cx, cy, r;
};

// The pattern's per-pixel matrix entry (20 bytes, direction included: a stand-in for the
// real hetero entry, which is 13 bytes without the direction, hosts/methods/hetero_entry.h).
struct PrimaryHit {
  std::int32_t object;  // -1: no hit
  float t;
  float dir[3];
};
static_assert(sizeof(PrimaryHit) == 20);
constexpr float kBackground[3] = {0.1f, 0.2f, 0.3f};

class Pattern {
 public:
  explicit Pattern(const PatternOptions& o) : o_(o) {
    std::uint32_t s = o.seed * 2654435761u + 12345u;
    auto next = [&] {
      s = s * 1664525u + 1013904223u;
      return float(s >> 8) / float(1 << 24);
    };
    // Discs in the left two thirds of the image, so the right third has frames with no hit.
    for (int i = 0; i < o.objects; ++i)
      discs_.push_back({next() * o.width * 0.5f, next() * o.height,
                        (0.08f + 0.12f * next()) * std::min(o.width, o.height)});
  }
  const PatternOptions& Options() const { return o_; }

  PrimaryHit Primary(int x, int y) const {
    PrimaryHit h{-1, 0, {0, 0, 0}};
    float dx = x + 0.5f - o_.width * 0.5f, dy = y + 0.5f - o_.height * 0.5f, dz = float(o_.width);
    float n = std::sqrt(dx * dx + dy * dy + dz * dz);
    h.dir[0] = dx / n, h.dir[1] = dy / n, h.dir[2] = dz / n;
    for (int i = 0; i < int(discs_.size()); ++i) {
      float ex = x + 0.5f - discs_[i].cx, ey = y + 0.5f - discs_[i].cy;
      float d2 = ex * ex + ey * ey, r2 = discs_[i].r * discs_[i].r;
      if (d2 > r2) continue;
      float t = 10.0f + i - std::sqrt(r2 - d2) / discs_[i].r;  // nearer at the centre
      if (h.object < 0 || t < h.t) h.object = i, h.t = t;
    }
    return h;
  }

  void Shade(const PrimaryHit& h, float* rgb) const {
    if (h.object < 0) {
      std::memcpy(rgb, kBackground, sizeof kBackground);
      return;
    }
    // A stand-in for secondary rays: float work whose cost --work scales.
    float a = h.t, b = h.dir[0], c = h.dir[1];
    for (int k = 0; k < o_.work; ++k) {
      a = std::sin(a + b) * 0.5f + 0.5f;
      b = std::cos(b * 1.7f + c) * 0.5f;
      c = std::sin(c * 2.3f + a) * 0.5f;
    }
    rgb[0] = 0.5f + 0.4f * a;  // ≥ 0.5: never the background's 0.1
    rgb[1] = std::fabs(b) + 0.25f * float(h.object);
    rgb[2] = std::fabs(c) + h.dir[2];
  }

 private:
  PatternOptions o_;
  std::vector<Disc> discs_;
};

std::string SetupText(const PatternOptions& o) {
  return nlohmann::json{{"width", o.width}, {"height", o.height}, {"objects", o.objects},
                        {"work", o.work},   {"seed", o.seed},     {"mode", o.mode}}
      .dump();
}

PatternOptions ParseSetup(const std::string& text) {
  try {
    auto j = nlohmann::json::parse(text);
    PatternOptions o;
    o.width = j.at("width"), o.height = j.at("height"), o.objects = j.at("objects");
    o.work = j.at("work"), o.seed = j.at("seed"), o.mode = j.at("mode");
    return o;
  } catch (const nlohmann::json::exception& e) {
    throw UserError(std::string("malformed mpi-check set-up: ") + e.what());
  }
}

class PatternWork : public FrameWork {
 public:
  explicit PatternWork(const PatternOptions& o) : pattern_(o) {}
  int ImageWidth() const override { return pattern_.Options().width; }
  int ImageHeight() const override { return pattern_.Options().height; }
  std::size_t BytesPerPixel() const override { return 3 * sizeof(float); }
  std::size_t SliceBytesPerPixel() const override {
    return pattern_.Options().mode == "hetero" ? sizeof(PrimaryHit) : 0;
  }
  void RenderFrame(const Frame& frame, std::span<const std::byte> slice,
                   std::span<std::byte> pixels) override {
    std::size_t i = 0;
    for (int y = frame.y0; y < frame.y0 + frame.height; ++y)
      for (int x = frame.x0; x < frame.x0 + frame.width; ++x, ++i) {
        PrimaryHit h;
        if (SliceBytesPerPixel())
          std::memcpy(&h, &slice[i * sizeof h], sizeof h);
        else
          h = pattern_.Primary(x, y);
        float rgb[3];
        pattern_.Shade(h, rgb);
        std::memcpy(&pixels[i * sizeof rgb], rgb, sizeof rgb);
      }
  }

 private:
  Pattern pattern_;
};

void WritePfm(const std::string& path, int width, int height, std::span<const std::byte> rgb) {
  std::string bytes = "PF\n" + std::to_string(width) + ' ' + std::to_string(height) +
                      "\n-1.0\n";  // little-endian, rows bottom-up
  const std::size_t row = std::size_t(width) * 12;
  for (int y = height - 1; y >= 0; --y)
    bytes.append(reinterpret_cast<const char*>(rgb.data() + y * row), row);
  WriteOutputFile(path, "PFM image", bytes);
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
  if (path.empty()) return;
  WriteOutputFile(path, "report", j.dump(2) + '\n');
}

struct CheckArgs {
  PatternOptions pattern;
  int frame = 32;
  bool local = false;
  std::string out, report;
  FramedOptions farm;
};

void RunCheck(CheckArgs& a) {
  PatternOptions& o = a.pattern;
  if (o.mode != "dist" && o.mode != "hetero")
    throw UserError("--mode must be dist or hetero, got '" + o.mode + "'");
  if (!a.report.empty() && (SameFile(a.report, a.out) || SameFile(a.report, CheckpointPathFor(a.out))))
    throw UserError("--report " + a.report + ": is the image or its checkpoint; choose another name");
  if (LauncherRank() == 0) {  // children write no file and hold frames only
    CheckOutputs({{"--out", a.out}, {"--report", a.report}});
    // The parent's image (12 bytes a pixel), the farm's copy and, for hetero, the matrix (40).
    CheckMemoryFits("mpi-check at " + std::to_string(o.width) + "x" + std::to_string(o.height),
                    {.perPixel = 72, .pixels = uint64_t(o.width) * uint64_t(o.height)});
  }
  if (a.local) {
    Pattern pattern(o);
    PatternWork work(o);
    std::vector<std::byte> image(std::size_t(o.width) * o.height * 12);
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        float rgb[3];
        pattern.Shade(pattern.Primary(x, y), rgb);
        std::memcpy(&image[(std::size_t(y) * o.width + x) * 12], rgb, 12);
      }
    WritePfm(a.out, o.width, o.height, image);
    return;
  }
  FrameGrid(o.width, o.height, a.frame);  // frame size 0 is an error before MPI starts
  auto factory = [](const std::string& setup) {
    return std::make_unique<PatternWork>(ParseSetup(setup));
  };
  Pattern pattern(o);
  std::vector<PrimaryHit> matrix;
  auto buildJob = [&] {
    FramedJob job;
    job.method = "mpi-check-" + o.mode;
    job.imageWidth = o.width, job.imageHeight = o.height, job.frameSize = a.frame;
    job.bytesPerPixel = 12;
    job.setup = SetupText(o);
    if (o.mode == "hetero") {
      auto start = std::chrono::steady_clock::now();
      matrix.resize(std::size_t(o.width) * o.height);
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x)
          matrix[std::size_t(y) * o.width + x] = pattern.Primary(x, y);
      job.parentPassSeconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      job.sliceFor = [&](const Frame& f) -> std::optional<std::vector<std::byte>> {
        std::vector<std::byte> slice =
            CutFrame(f, std::as_bytes(std::span(matrix)), o.width, sizeof(PrimaryHit));
        for (std::size_t i = 0; i < f.PixelCount(); ++i) {
          std::int32_t object;
          std::memcpy(&object, &slice[i * sizeof(PrimaryHit)], 4);
          if (object >= 0) return slice;
        }
        return std::nullopt;
      };
      job.fillDegenerate = [](const Frame& f, std::span<std::byte> pixels) {
        for (std::size_t i = 0; i < f.PixelCount(); ++i)
          std::memcpy(&pixels[i * 12], kBackground, 12);
      };
    }
    return job;
  };
  a.farm.checkpointPath = CheckpointPathFor(a.out);
  if (ServeIfChild(o.mode, factory)) return;  // a child: served frames, no output
  const FramedResult result = RenderFrames(buildJob(), a.farm);
  WritePfm(a.out, o.width, o.height, result.image);
  WriteJson(a.report, result.report.Json());
  RemoveCheckpoint(result.checkpointPath);  // only now: the outputs are on disk
}

CommandRegistration reg("mpi-check", [](CLI::App& program) {
  auto args = std::make_shared<CheckArgs>();
  auto* cmd = program.add_subcommand(
      "mpi-check",
      "Run the frame farm of dist/hetero on a synthetic pattern (check an MPI set-up; "
      "launch with mpirun -np K+1)");
  cmd->add_option("--mode", args->pattern.mode, "dist or hetero")->capture_default_str();
  AddInteger(*cmd, "--width", args->pattern.width, 1, kMaxResolution, "image width");
  AddInteger(*cmd, "--height", args->pattern.height, 1, kMaxResolution, "image height");
  AddInteger(*cmd, "--objects", args->pattern.objects, 0, 1000, "discs in the pattern");
  AddInteger(*cmd, "--work", args->pattern.work, 0, 100000000, "stand-in shading iterations per pixel");
  AddInteger(*cmd, "--seed", args->pattern.seed, std::uint32_t(0), UINT32_MAX, "pattern seed");
  AddInteger(*cmd, "--frame", args->frame, 1, kMaxResolution, "frame size F (F×F frames)");
  cmd->add_flag("--local", args->local, "render in this process, without MPI (the reference)");
  cmd->add_option("--out", args->out, "output image (.pfm)")->required();
  cmd->add_option("--report", args->report, "JSON report (parent)");
  cmd->add_flag("--resume", args->farm.resume,
                "render only the frames missing from the checkpoint");
  AddNumber(*cmd, "--child-timeout", args->farm.childTimeoutSeconds, kMinChildTimeoutSeconds, kNoUpperEnd,
            "seconds before a silent child holding frames is declared lost");
  AddInteger(*cmd, "--in-flight", args->farm.framesInFlight, 1, kMaxFramesInFlight,
             "frames handed to a child at once");
  cmd->callback([args] { RunCheck(*args); });
});

}  // namespace
}  // namespace zephyr
