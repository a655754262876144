// The second worked example of docs/programming.md (tools/examples/blur.h): the 3x3 blur on
// the emulated array equals the plain C++ version on random pixels (every target), and
// through a PNG file of a size that is not whole blocks.
#include "tools/examples/blur.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "tests/bitserial/testing.h"
#include "tests/farm/mpi_launch.h"

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

// A PNG's header is checked against the memory budget before its pixels are read: a small
// file claiming 20000x20000 pixels is a clear refusal with the sizes (issue 39: an uncaught
// std::bad_alloc), and so is an input that is no regular file.
TEST(ToolsBlur, APngClaimingMorePixelsThanMemoryIsRefusedFromItsHeader) {
  testing::TempDir dir;
  auto crc = [](const std::string& bytes) {
    uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(uint32_t(data.size())) + type + data + be32(crc(type + data));
  };
  // The signature, an IHDR of 20000x20000 8-bit RGB, and IEND: a header and no pixels.
  const std::string ihdr = be32(20000) + be32(20000) + std::string{8, 2, 0, 0, 0};
  // An IDAT of an empty zlib stream: libpng reads the header up to the first IDAT.
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) +
                          chunk("IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8)) +
                          chunk("IEND", "");
  const std::string in = dir / "huge.png";
  std::ofstream(in, std::ios::binary) << png;
  const PngSize size = ReadPngSize(in);
  EXPECT_EQ(size.width, 20000);
  EXPECT_EQ(size.height, 20000);
  try {
    BlurPng(in, dir / "out.png", "wavetracer");
    ADD_FAILURE() << "read";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("example_blur of a 20000x20000 PNG needs about"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));
  try {
    ReadPng("/dev/zero");
    ADD_FAILURE() << "read";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: is not a regular file"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace zephyr::examples
