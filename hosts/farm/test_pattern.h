// hosts/farm/test_pattern.h — the frame farm's synthetic test pattern (`zephyr mpi-check`,
// hosts/cmd/mpi_check.cpp): the farm with no scene and no tracer, to check an MPI
// installation (a hostfile, a cluster) and to test the farm itself.
//
// The pattern imitates both methods: in "dist" mode children compute each pixel's "primary
// hit" (the nearest of a few discs) and its colour; in "hetero" mode the parent computes the
// per-pixel matrix {object, t, direction} and sends only frames where some pixel hit a disc,
// children colouring from the matrix. RenderPatternLocally computes the same image in one
// process without MPI — the reference the farm must reproduce bit for bit. Pixels are 3 floats.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "hosts/farm/farm.h"

namespace zephyr {

struct PatternOptions {
  int width = 48, height = 32, objects = 3, work = 1;
  std::uint32_t seed = 1;
  std::string mode = "dist";  // dist or hetero
};

struct PatternDisc {
  float cx, cy, r;
};

// The pattern's per-pixel matrix entry (20 bytes, direction included: a stand-in for the
// real hetero entry, which is 13 bytes without the direction, hosts/methods/hetero_entry.h).
struct PatternHit {
  std::int32_t object;  // -1: no hit
  float t;
  float dir[3];
};
static_assert(sizeof(PatternHit) == 20);
inline constexpr float kPatternBackground[3] = {0.1f, 0.2f, 0.3f};

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

  PatternHit Primary(int x, int y) const {
    PatternHit h{-1, 0, {0, 0, 0}};
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

  void Shade(const PatternHit& h, float* rgb) const {
    if (h.object < 0) {
      std::memcpy(rgb, kPatternBackground, sizeof kPatternBackground);
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
  std::vector<PatternDisc> discs_;
};

// The options as the parent sends them to the children, and back (UserError for a malformed
// set-up).
std::string PatternSetupText(const PatternOptions& o);
PatternOptions ParsePatternSetup(const std::string& text);

// A child's work: a frame of the pattern, from the matrix slice (hetero) or from nothing (dist).
class PatternWork : public FrameWork {
 public:
  explicit PatternWork(const PatternOptions& o) : pattern_(o) {}
  int ImageWidth() const override { return pattern_.Options().width; }
  int ImageHeight() const override { return pattern_.Options().height; }
  std::size_t BytesPerPixel() const override { return 3 * sizeof(float); }
  std::size_t SliceBytesPerPixel() const override;
  void RenderFrame(const Frame& frame, std::span<const std::byte> slice,
                   std::span<std::byte> pixels) override;

 private:
  Pattern pattern_;
};

// The image in this process (12 bytes a pixel, row-major): the farm's reference.
std::vector<std::byte> RenderPatternLocally(const PatternOptions& o);

// The farm's job for the pattern in frames of `frameSize` pixels; in hetero mode the parent's
// matrix is computed into `matrix` (which must outlive the job: the job's slices read it).
FramedJob PatternJob(const PatternOptions& o, int frameSize, std::vector<PatternHit>& matrix);

}  // namespace zephyr
