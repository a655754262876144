// hosts/farm/frame.h — frames: the rectangular tiles the distributed and heterogeneous methods
// hand to their children (paper §4: "the image is divided into frames").
//
// An image of W×H pixels is cut into F×F frames in row-major order; the frames on the right
// and bottom edges are smaller when F does not divide W or H. Frame ids are their index in
// that order, so the parent, the children and a checkpoint file agree on them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

namespace zephyr {

struct Frame {
  int id = 0;
  int x0 = 0, y0 = 0;         // top-left pixel (x right, y down)
  int width = 0, height = 0;  // ≥ 1
  std::size_t PixelCount() const { return std::size_t(width) * std::size_t(height); }
  bool operator==(const Frame&) const = default;
};

// The frames of an image. Throws UserError for a frame size < 1 or an empty image.
class FrameGrid {
 public:
  FrameGrid(int imageWidth, int imageHeight, int frameSize);

  int ImageWidth() const { return width_; }
  int ImageHeight() const { return height_; }
  int FrameSize() const { return frameSize_; }
  int Columns() const { return columns_; }
  int Rows() const { return rows_; }
  int Count() const { return columns_ * rows_; }
  Frame At(int id) const;
  std::vector<Frame> All() const;

 private:
  int width_, height_, frameSize_, columns_, rows_;
};

// Copies a frame's pixels (frame-local rows, bytesPerPixel each) into / out of an image
// stored row-major with the same pixel size.
void PasteFrame(const Frame& frame, std::span<const std::byte> framePixels,
                std::span<std::byte> image, int imageWidth, std::size_t bytesPerPixel);
std::vector<std::byte> CutFrame(const Frame& frame, std::span<const std::byte> image,
                                int imageWidth, std::size_t bytesPerPixel);

// The parent's queue of frames still to render: frames go out in id order, on demand, and a
// frame whose child was lost goes back to the front so it is handed out next.
class FrameQueue {
 public:
  explicit FrameQueue(std::vector<int> frameIds) : pending_(frameIds.begin(), frameIds.end()) {}
  bool Empty() const { return pending_.empty(); }
  std::size_t Size() const { return pending_.size(); }
  int Next();  // ZEPHYR_CHECK: not empty
  void Requeue(int frameId) { pending_.push_front(frameId); }

 private:
  std::deque<int> pending_;
};

}  // namespace zephyr
