#include "hosts/trace/image.h"

#include <png.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "fixed/check.h"
#include "hosts/io/output_file.h"

namespace zephyr {

void Image::Paste(int x0, int y0, int w, int h, const std::vector<Vec3>& block) {
  ZEPHYR_CHECK_EQ(block.size(), size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) At(x0 + x, y0 + y) = block[size_t(y) * w + x];
}

uint8_t ToByte(double c) {
  if (!(c > 0)) return 0;  // also NaN
  if (c >= 1) return 255;
  return uint8_t(std::lround(c * 255.0));
}

namespace {
struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<FILE, FileCloser>;
}  // namespace

void WritePng(const std::string& path, const Image& image) {
  OutputFile f(path, "PNG file");  // `path` is replaced only once every byte is on disk
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw UserError(path + ": libpng could not start");
  }
  std::vector<uint8_t> row(size_t(image.width) * 3);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw UserError(path + ": libpng failed while writing (nothing was written under that name)");
  }
  png_init_io(png, f.Stream());
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Vec3& c = image.At(x, y);
      row[3 * x] = ToByte(c.x);
      row[3 * x + 1] = ToByte(c.y);
      row[3 * x + 2] = ToByte(c.z);
    }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  f.Commit();
}

Image ReadPng(const std::string& path) {
  // The low-level API on purpose: the simplified one converts files tagged gAMA 1.0 (as
  // POV-Ray writes them with File_Gamma=1.0) to sRGB, and we compare raw 8-bit values.
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) throw UserError(path + ": cannot open the PNG file");
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw UserError(path + ": libpng could not start");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw UserError(path + ": not a readable PNG file");
  }
  png_init_io(png, f.get());
  png_read_png(png, info,
               PNG_TRANSFORM_STRIP_16 | PNG_TRANSFORM_STRIP_ALPHA | PNG_TRANSFORM_PACKING |
                   PNG_TRANSFORM_EXPAND | PNG_TRANSFORM_GRAY_TO_RGB,
               nullptr);
  const int w = int(png_get_image_width(png, info)), h = int(png_get_image_height(png, info));
  png_bytepp rows = png_get_rows(png, info);
  Image out(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      out.At(x, y) = {rows[y][3 * x] / 255.0, rows[y][3 * x + 1] / 255.0,
                      rows[y][3 * x + 2] / 255.0};
  png_destroy_read_struct(&png, &info, nullptr);
  return out;
}

double Psnr(const Image& a, const Image& b) {
  ZEPHYR_CHECK(a.width == b.width && a.height == b.height);
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double d = double(ToByte(a.pixels[i][c])) - double(ToByte(b.pixels[i][c]));
      sum += d * d;
    }
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  const double mse = sum / (3.0 * a.pixels.size());
  return 10 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace zephyr
