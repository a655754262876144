// Hardware-fidelity test 4: PE memory capacity, virtual-PE layers and the layout.
#include <gtest/gtest.h>

#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(BitserialMemory, ExactFillWorksOneBitMoreFails) {
  PeMemory mem(2048, 32 * 1024 * 8, 1);
  mem.Allocate("block", 2048, Space::Internal);
  mem.Allocate("heap", 32 * 1024 * 8, Space::External);
  EXPECT_EQ(mem.Used(Space::Internal), mem.Capacity(Space::Internal));
  std::string e = ErrorOf([&] { mem.Allocate("extra", 1, Space::Internal); });
  EXPECT_NE(e.find("'extra'"), std::string::npos) << e;
  EXPECT_NE(e.find("needs 1 bits"), std::string::npos) << e;
  EXPECT_NE(e.find("0 of 2048"), std::string::npos) << e;
  EXPECT_FALSE(ErrorOf([&] { mem.Allocate("extra2", 1, Space::External); }).empty());
  EXPECT_FALSE(ErrorOf([&] { mem.Allocate("auto", 1); }).empty());
}

TEST(BitserialMemory, VirtualLayersSplitTheMemory) {
  Machine m(Profile("wavetracer"), 384 * 384);
  EXPECT_EQ(m.Layers(), 18);
  EXPECT_EQ(m.WordsPerPlane(), 18u * 128u);
  EXPECT_EQ(m.Memory().Capacity(Space::Internal), 2048 / 18);
  EXPECT_EQ(m.Memory().Capacity(Space::External), 32 * 1024 * 8 / 18);
  // Exactly filling a virtual PE's internal share works through the Multi layer...
  Multi big(m, Format::Signed(100, 0), "big", Space::Internal);
  Multi rest(m, Format::Unsigned(2048 / 18 - 101, 0), "rest", Space::Internal);
  EXPECT_EQ(m.Memory().Used(Space::Internal), 2048 / 18);
  // ...one bit more fails, naming the variable; without a space it goes external.
  std::string e = ErrorOf([&] { Multi x(m, Format::Unsigned(1, 0), "oneMore", Space::Internal); });
  EXPECT_NE(e.find("'oneMore'"), std::string::npos) << e;
  EXPECT_NE(e.find("18 virtual-PE layers"), std::string::npos) << e;
  Multi spill(m, Format::Unsigned(1, 0), "spill");
  EXPECT_EQ(spill.GetSpace(), Space::External);
  EXPECT_EQ(Machine(Profile("wavetracer"), 8193).Layers(), 2);
  EXPECT_EQ(Machine(Profile("wavetracer"), 8192).Layers(), 1);
}

TEST(BitserialMemory, LayoutIsReproducibleAndPrintable) {
  auto program = [] {
    Machine m(Profile("wavetracer"));
    Multi a(m, Format::Signed(15, 8), "a"), b(m, Format::Signed(15, 8), "b");
    std::string map;
    {
      Multi t = a * b;
      Multi u = a + b;
      map = m.Memory().Map();
    }
    Multi c(m, Format::Unsigned(3, 0), "c");  // first fit reuses the freed space
    return map + m.Memory().Map();
  };
  const std::string first = program();
  EXPECT_EQ(first, program());
  EXPECT_NE(first.find("a\n"), std::string::npos) << first;
  EXPECT_NE(first.find("       48..50          3 bits  c"), std::string::npos) << first;
}

}  // namespace
}  // namespace zephyr::bitserial
