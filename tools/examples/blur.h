// tools/examples/blur.h — a 3×3 box blur of a PNG as a program for the emulated Zephyr
// (docs/programming.md): one 8-bit channel value per virtual PE, the nine-pixel sum by
// shifts over the virtual mesh, the mean by a division by a uni 9. Blur3x3Plain is the
// same in plain C++; BlurPng runs the array version on every channel of a PNG file and
// checks it against the plain one.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/trace/image.h"

namespace zephyr::examples {

// The blur of `pix` (u8.0, one pixel per virtual PE of `grid`): each output is the mean of
// the pixel and its eight neighbours, pixels outside the grid counting as 0, rounded to
// nearest (halves up): floor(sum / 9 + 1/2).
inline bitserial::Multi Blur3x3(const bitserial::Multi& pix, const bitserial::MeshShape& grid) {
  using bitserial::Multi;
  const fixed::Format sum = fixed::Format::Unsigned(12, 0);  // 9 × 255 = 2295
  const Multi row =
      Add(Add(MeshShift(pix, grid, 0, 1), MeshShift(pix, grid, 0, -1), sum), pix, sum);
  const Multi block =
      Add(Add(MeshShift(row, grid, 1, 1), MeshShift(row, grid, 1, -1), sum), row, sum);
  const bitserial::Uni nine{fixed::Fixed{fixed::Format::Unsigned(4, 0), 9}};
  return Div(block, nine, fixed::Format::Unsigned(8, 0), {fixed::Rounding::kNearest});
}

// The same on a plain w × h grid of 0..255 values (row-major).
inline std::vector<int64_t> Blur3x3Plain(const std::vector<int64_t>& pix, int w, int h) {
  std::vector<int64_t> out(pix.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int64_t s = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (x + dx >= 0 && x + dx < w && y + dy >= 0 && y + dy < h)
            s += pix[x + dx + w * (y + dy)];
      out[x + w * y] = (2 * s + 9) / 18;
    }
  return out;
}

struct BlurResult {
  int width = 0, height = 0;  // the image
  int gridW = 0, gridH = 0;   // the virtual grid: the image padded with 0 to whole blocks
  int layers = 0;
  double cyclesPerChannel = 0;  // the array program, one channel
  std::string reportTable;      // its cycle report (the last channel's)
};

// Blurs every channel of the PNG `in` on a machine of `profile` and writes `out`. UserError
// for an unreadable or unwritable file, or if the array and the plain version differ.
// `overrides` are --set's "name=value" entries (bitserial::MachineProfile::Override).
inline BlurResult BlurPng(const std::string& in, const std::string& out, const std::string& profile,
                          const std::vector<std::string>& overrides = {}) {
  // The header first, against the memory budget (docs/errors.md, "Memory"): a small file may
  // claim 20000x20000 pixels. Per pixel: the image and the result (24 bytes each), the host's
  // 64-bit copies of a channel and its plain blur (16), the array's planes (~14), with margin.
  const PngSize size = ReadPngSize(in);
  CheckMemoryFits(fmt::format("example_blur of a {}x{} PNG", size.width, size.height),
                  {.perPixel = 128, .pixels = uint64_t(size.width) * uint64_t(size.height)});
  const Image image = ReadPng(in);
  bitserial::MachineProfile prof = bitserial::Profile(profile);
  for (const std::string& s : overrides) prof.Override(s);
  const std::vector<int>& mesh = prof.shapes.at(0).extent;
  if (mesh.size() != 2)
    throw UserError("the blur maps an image onto a 2-D mesh; profile '" + prof.name +
                    "' has the mesh " + prof.shapes.at(0).Name());
  BlurResult r;
  r.width = image.width, r.height = image.height;
  r.gridW = (image.width + mesh[0] - 1) / mesh[0] * mesh[0];
  r.gridH = (image.height + mesh[1] - 1) / mesh[1] * mesh[1];
  bitserial::Machine m(prof, int64_t{r.gridW} * r.gridH);
  r.layers = m.Layers();
  const bitserial::MeshShape grid{{r.gridW, r.gridH}};
  Image result(image.width, image.height);
  for (int c = 0; c < 3; ++c) {
    std::vector<int64_t> pix(m.VirtualPes(), 0), plain(image.width * size_t(image.height));
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        plain[x + size_t(image.width) * y] = pix[x + size_t(r.gridW) * y] =
            ToByte(image.At(x, y)[c]);
    bitserial::Multi p(m, fixed::Format::Unsigned(8, 0), "pixel");
    p.LoadRaw(pix);
    m.Report().Clear();
    const bitserial::Multi blurred = Blur3x3(p, grid);
    r.cyclesPerChannel = m.Report().TotalCycles();
    const std::vector<int64_t> want = Blur3x3Plain(plain, image.width, image.height);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const int64_t got = blurred.At(x + int64_t{r.gridW} * y).raw.convert_to<int64_t>();
        if (got != want[x + size_t(image.width) * y])
          throw UserError(
              fmt::format("{}: pixel ({}, {}) channel {}: the array gives {}, plain "
                          "C++ {}",
                          in, x, y, c, got, want[x + size_t(image.width) * y]));
        Vec3& px = result.At(x, y);
        px = Vec3(c == 0 ? got / 255.0 : px.x, c == 1 ? got / 255.0 : px.y,
                  c == 2 ? got / 255.0 : px.z);
      }
  }
  r.reportTable = m.Report().Table();
  WritePng(out, result);
  return r;
}

}  // namespace zephyr::examples
