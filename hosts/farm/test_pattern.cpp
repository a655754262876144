// hosts/farm/test_pattern.cpp — the frame farm's synthetic test pattern
// (hosts/farm/test_pattern.h).
#include "hosts/farm/test_pattern.h"

#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>

#include "fixed/check.h"
#include "hosts/farm/frame.h"

namespace zephyr {

std::string PatternSetupText(const PatternOptions& o) {
  return nlohmann::json{{"width", o.width}, {"height", o.height}, {"objects", o.objects},
                        {"work", o.work},   {"seed", o.seed},     {"mode", o.mode}}
      .dump();
}

PatternOptions ParsePatternSetup(const std::string& text) {
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

std::size_t PatternWork::SliceBytesPerPixel() const {
  return pattern_.Options().mode == "hetero" ? sizeof(PatternHit) : 0;
}

void PatternWork::RenderFrame(const Frame& frame, std::span<const std::byte> slice,
                              std::span<std::byte> pixels) {
  std::size_t i = 0;
  for (int y = frame.y0; y < frame.y0 + frame.height; ++y)
    for (int x = frame.x0; x < frame.x0 + frame.width; ++x, ++i) {
      PatternHit h;
      if (SliceBytesPerPixel())
        std::memcpy(&h, &slice[i * sizeof h], sizeof h);
      else
        h = pattern_.Primary(x, y);
      float rgb[3];
      pattern_.Shade(h, rgb);
      std::memcpy(&pixels[i * sizeof rgb], rgb, sizeof rgb);
    }
}

std::vector<std::byte> RenderPatternLocally(const PatternOptions& o) {
  const Pattern pattern(o);
  std::vector<std::byte> image(std::size_t(o.width) * o.height * 12);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      float rgb[3];
      pattern.Shade(pattern.Primary(x, y), rgb);
      std::memcpy(&image[(std::size_t(y) * o.width + x) * 12], rgb, 12);
    }
  return image;
}

FramedJob PatternJob(const PatternOptions& o, int frameSize, std::vector<PatternHit>& matrix) {
  FramedJob job;
  job.method = "mpi-check-" + o.mode;
  job.imageWidth = o.width, job.imageHeight = o.height, job.frameSize = frameSize;
  job.bytesPerPixel = 12;
  job.setup = PatternSetupText(o);
  if (o.mode != "hetero") return job;
  const Pattern pattern(o);
  const auto start = std::chrono::steady_clock::now();
  matrix.resize(std::size_t(o.width) * o.height);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) matrix[std::size_t(y) * o.width + x] = pattern.Primary(x, y);
  job.parentPassSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int width = o.width;
  job.sliceFor = [&matrix, width](const Frame& f) -> std::optional<std::vector<std::byte>> {
    std::vector<std::byte> slice =
        CutFrame(f, std::as_bytes(std::span(matrix)), width, sizeof(PatternHit));
    for (std::size_t i = 0; i < f.PixelCount(); ++i) {
      std::int32_t object;
      std::memcpy(&object, &slice[i * sizeof(PatternHit)], 4);
      if (object >= 0) return slice;
    }
    return std::nullopt;
  };
  job.fillDegenerate = [](const Frame& f, std::span<std::byte> pixels) {
    for (std::size_t i = 0; i < f.PixelCount(); ++i)
      std::memcpy(&pixels[i * 12], kPatternBackground, 12);
  };
  return job;
}

}  // namespace zephyr
