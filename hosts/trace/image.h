// hosts/trace/image.h — an RGB image in linear floating point, and PNG files (libpng).
//
// Colours go to 8 bits by clamping each channel to [0, 1] and rounding c·255 to the nearest
// integer: no gamma (docs/shading.md). ToByte is the one place that mapping lives.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hosts/scene/geometry.h"

namespace zephyr {

struct Image {
  int width = 0, height = 0;
  std::vector<Vec3> pixels;  // row-major, top row first, linear RGB

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(size_t(w) * h) {}
  Vec3& At(int x, int y) { return pixels[size_t(y) * width + x]; }
  const Vec3& At(int x, int y) const { return pixels[size_t(y) * width + x]; }
  // Copies a w×h block (row-major) to (x0, y0).
  void Paste(int x0, int y0, int w, int h, const std::vector<Vec3>& block);
};

uint8_t ToByte(double channel);

// 8-bit RGB PNG, written atomically (hosts/io/output_file.h: an existing file of that name
// stays intact unless the whole new one is on disk). Errors (cannot create the file, a
// full disk, libpng failure) are UserErrors.
void WritePng(const std::string& path, const Image& image);
// Reads an 8-bit (or 16-bit) RGB/RGBA/grey PNG into channels in [0, 1]. UserError for a path
// that is no regular file (fixed/input_file.h), a file that is no PNG, or an image whose
// pixels cannot be allocated (with its size).
Image ReadPng(const std::string& path);
// A PNG's width and height from its header alone (the same errors): a program checks the
// image's memory against its budget before it reads the pixels.
struct PngSize {
  int64_t width = 0, height = 0;
};
PngSize ReadPngSize(const std::string& path);

// Peak signal-to-noise ratio in dB over the 8-bit values of two same-size images
// (infinity when they are identical).
double Psnr(const Image& a, const Image& b);

}  // namespace zephyr
