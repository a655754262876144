#include "hosts/farm/frame.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "fixed/check.h"

namespace zephyr {

FrameGrid::FrameGrid(int imageWidth, int imageHeight, int frameSize)
    : width_(imageWidth), height_(imageHeight), frameSize_(frameSize) {
  if (frameSize < 1)
    throw UserError("frame size must be at least 1 pixel (got " + std::to_string(frameSize) + ")");
  if (imageWidth < 1 || imageHeight < 1)
    throw UserError("image size must be at least 1×1 (got " + std::to_string(imageWidth) + "×" +
                    std::to_string(imageHeight) + ")");
  columns_ = (width_ + frameSize_ - 1) / frameSize_;
  rows_ = (height_ + frameSize_ - 1) / frameSize_;
}

Frame FrameGrid::At(int id) const {
  ZEPHYR_CHECK(id >= 0 && id < Count());
  Frame f;
  f.id = id;
  f.x0 = (id % columns_) * frameSize_;
  f.y0 = (id / columns_) * frameSize_;
  f.width = std::min(frameSize_, width_ - f.x0);
  f.height = std::min(frameSize_, height_ - f.y0);
  return f;
}

std::vector<Frame> FrameGrid::All() const {
  std::vector<Frame> frames;
  frames.reserve(Count());
  for (int id = 0; id < Count(); ++id) frames.push_back(At(id));
  return frames;
}

void PasteFrame(const Frame& frame, std::span<const std::byte> framePixels,
                std::span<std::byte> image, int imageWidth, std::size_t bytesPerPixel) {
  const std::size_t row = std::size_t(frame.width) * bytesPerPixel;
  ZEPHYR_CHECK_EQ(framePixels.size(), row * frame.height);
  for (int y = 0; y < frame.height; ++y) {
    std::size_t at = (std::size_t(frame.y0 + y) * imageWidth + frame.x0) * bytesPerPixel;
    ZEPHYR_CHECK_LE(at + row, image.size());
    std::memcpy(image.data() + at, framePixels.data() + y * row, row);
  }
}

std::vector<std::byte> CutFrame(const Frame& frame, std::span<const std::byte> image,
                                int imageWidth, std::size_t bytesPerPixel) {
  const std::size_t row = std::size_t(frame.width) * bytesPerPixel;
  std::vector<std::byte> out(row * frame.height);
  for (int y = 0; y < frame.height; ++y) {
    std::size_t at = (std::size_t(frame.y0 + y) * imageWidth + frame.x0) * bytesPerPixel;
    ZEPHYR_CHECK_LE(at + row, image.size());
    std::memcpy(out.data() + y * row, image.data() + at, row);
  }
  return out;
}

int FrameQueue::Next() {
  ZEPHYR_CHECK(!pending_.empty());
  int id = pending_.front();
  pending_.pop_front();
  return id;
}

}  // namespace zephyr
