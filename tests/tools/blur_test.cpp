// The second worked example of docs/programming.md (tools/examples/blur.h): the 3x3 blur on
// the emulated array equals the plain C++ version on random pixels (every target), and
// through a PNG file of a size that is not whole blocks.
#include "tools/examples/blur.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "tests/bitserial/testing.h"

namespace zephyr::examples {
namespace {

TEST(ToolsBlur, EqualsThePlainVersionEveryTarget) {
  bitserial::testutil::ForEachTarget([] {
    bitserial::Machine m(bitserial::Profile("wavetracer"), 128 * 256);  // 2x2 blocks, 4 layers
    std::mt19937_64 rng(9);
    std::vector<int64_t> pix(m.VirtualPes());
    for (auto& p : pix) p = static_cast<int64_t>(rng() % 256);
    pix[0] = pix[1] = pix[128] = pix[129] = 255;  // a corner of bright pixels
    bitserial::Multi p(m, fixed::Format::Unsigned(8, 0), "p");
    p.LoadRaw(pix);
    const bitserial::Multi b = Blur3x3(p, bitserial::MeshShape{{128, 256}});
    EXPECT_EQ(b.ReadRaw(), Blur3x3Plain(pix, 128, 256)) << m.Kernels().target;
  });
}

TEST(ToolsBlur, BlursAPngFile) {
  const auto dir = std::filesystem::temp_directory_path() / "zephyr_blur_test";
  std::filesystem::create_directories(dir);
  Image img(70, 45);  // padded to 128x128 on the WaveTracer's 64x128 mesh
  std::mt19937_64 rng(2);
  for (auto& px : img.pixels)
    px = Vec3((rng() % 256) / 255.0, (rng() % 256) / 255.0, (rng() % 256) / 255.0);
  WritePng((dir / "in.png").string(), img);
  const BlurResult r = BlurPng((dir / "in.png").string(), (dir / "out.png").string(), "wavetracer");
  EXPECT_EQ(r.gridW, 128);
  EXPECT_EQ(r.gridH, 128);
  EXPECT_GT(r.cyclesPerChannel, 0);
  const Image out = ReadPng((dir / "out.png").string());
  ASSERT_EQ(out.width, 70);
  // The centre pixel of the red channel is the rounded mean of its 3x3 block.
  int64_t s = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) s += ToByte(img.At(35 + dx, 20 + dy).x);
  EXPECT_EQ(ToByte(out.At(35, 20).x), (2 * s + 9) / 18);
  EXPECT_THROW(BlurPng((dir / "missing.png").string(), (dir / "o.png").string(), "wavetracer"),
               UserError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace zephyr::examples
