#include "hosts/trace/image.h"

#include <fmt/format.h>
#include <png.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <new>

#include "fixed/check.h"
#include "fixed/input_file.h"
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

namespace {
// A PNG being read: the file (a regular file only, fixed/input_file.h, opened) and libpng's
// structures, destroyed with it. Every libpng error longjmps to the caller's setjmp, which
// must be in the function that makes the libpng calls.
struct PngInput {
  std::string shown;  // the path as messages show it
  File file;
  png_structp png = nullptr;
  png_infop info = nullptr;

  explicit PngInput(const std::string& path) : shown(PrintablePath(path)) {
    CheckInputFile(path, {"the PNG file", "a PNG file"}, std::uintmax_t(1) << 30);
    file.reset(std::fopen(path.c_str(), "rb"));
    if (!file) throw UserError(shown + ": cannot open the PNG file");
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    info = png ? png_create_info_struct(png) : nullptr;
    if (!info) {
      png_destroy_read_struct(&png, nullptr, nullptr);
      throw UserError(shown + ": libpng could not start");
    }
    png_init_io(png, file.get());
  }
  ~PngInput() { png_destroy_read_struct(&png, &info, nullptr); }
  PngInput(const PngInput&) = delete;
  PngInput& operator=(const PngInput&) = delete;
  [[noreturn]] void Unreadable() const { throw UserError(shown + ": not a readable PNG file"); }
};
}  // namespace

PngSize ReadPngSize(const std::string& path) {
  PngInput in(path);
  if (setjmp(png_jmpbuf(in.png))) in.Unreadable();
  png_read_info(in.png, in.info);
  return {int64_t(png_get_image_width(in.png, in.info)),
          int64_t(png_get_image_height(in.png, in.info))};
}

Image ReadPng(const std::string& path) {
  // The low-level API on purpose: the simplified one converts files tagged gAMA 1.0 (as
  // POV-Ray writes them with File_Gamma=1.0) to sRGB, and we compare raw 8-bit values.
  // Row by row, into an image allocated once the header is read: a header that claims more
  // pixels than memory holds is a UserError with the sizes, not std::bad_alloc.
  PngInput in(path);
  png_structp png = in.png;
  png_infop info = in.info;
  const std::string& shown = in.shown;
  Image out;
  std::vector<png_byte> row;
  if (setjmp(png_jmpbuf(png))) in.Unreadable();
  png_read_info(png, info);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_packing(png);
  png_set_expand(png);
  png_set_gray_to_rgb(png);
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const uint32_t w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  const size_t rowBytes = png_get_rowbytes(png, info);
  bool allocated = false;
  try {
    if (passes > 1) {  // interlaced: every row is revisited, so the whole 8-bit image is kept
      row.resize(rowBytes * h);
    } else {
      row.resize(rowBytes);
    }
    out = Image(int(w), int(h));
    allocated = true;
  } catch (const std::bad_alloc&) {
  }
  if (!allocated)
    throw UserError(fmt::format(
        "{}: the PNG is {}x{} pixels: its {:.2f} GiB in memory cannot be allocated", shown, w, h,
        (double(w) * h * sizeof(Vec3) + double(row.capacity())) / double(1 << 30)));
  for (int pass = 0; pass < passes; ++pass)
    for (uint32_t y = 0; y < h; ++y) {
      png_bytep r = passes > 1 ? row.data() + rowBytes * y : row.data();
      png_read_row(png, r, nullptr);
      if (passes == 1 || pass + 1 == passes)
        for (uint32_t x = 0; x < w; ++x)
          out.At(int(x), int(y)) = {r[3 * x] / 255.0, r[3 * x + 1] / 255.0, r[3 * x + 2] / 255.0};
    }
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
