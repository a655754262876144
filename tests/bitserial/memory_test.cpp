// Hardware-fidelity test 4: PE memory capacity, virtual-PE layers and the layout.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <vector>

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
  mem.Allocate("block", 2048, Space::kInternal);
  mem.Allocate("heap", 32 * 1024 * 8, Space::kExternal);
  EXPECT_EQ(mem.Used(Space::kInternal), mem.Capacity(Space::kInternal));
  std::string e = ErrorOf([&] { mem.Allocate("extra", 1, Space::kInternal); });
  EXPECT_NE(e.find("'extra'"), std::string::npos) << e;
  EXPECT_NE(e.find("needs 1 bits"), std::string::npos) << e;
  EXPECT_NE(e.find("0 of 2048"), std::string::npos) << e;
  EXPECT_FALSE(ErrorOf([&] { mem.Allocate("extra2", 1, Space::kExternal); }).empty());
  EXPECT_FALSE(ErrorOf([&] { mem.Allocate("auto", 1); }).empty());
}

// First fit at its boundaries, for every layer count that leaves room for the layout: a freed
// gap takes a request of exactly its size (at its address) but not one bit more; a request
// goes to the first gap in address order that holds it, past smaller ones; the last bit of
// the capacity is usable and the next is not; freeing everything gives the whole space back.
TEST(BitserialMemory, FirstFitAtItsBoundaries) {
  for (int layers = 1; layers <= 64; ++layers) {
    PeMemory mem(2048, 32 * 1024 * 8, layers);
    const int64_t cap = mem.Capacity(Space::kInternal);
    ASSERT_EQ(cap, 2048 / layers) << layers;
    const std::string at = " with " + std::to_string(layers) + " layers";
    // Layout: a(1) b(g1) c(1) d(g2) e(rest), g1 < g2, then b and d freed: two gaps.
    const int64_t g1 = std::max<int64_t>(1, cap / 8), g2 = g1 + 1, rest = cap - 2 - g1 - g2;
    ASSERT_GE(rest, 1) << at;
    const Allocation a = mem.Allocate("a", 1, Space::kInternal),
                     b = mem.Allocate("b", g1, Space::kInternal),
                     c = mem.Allocate("c", 1, Space::kInternal),
                     d = mem.Allocate("d", g2, Space::kInternal),
                     e = mem.Allocate("e", rest, Space::kInternal);
    EXPECT_EQ(e.address + e.bits, cap) << at;  // the last bit is usable...
    EXPECT_FALSE(ErrorOf([&] { mem.Allocate("over", 1, Space::kInternal); }).empty())
        << at;  // ...the next not
    mem.Free(b.id), mem.Free(d.id);
    // One bit more than both gaps fits nowhere.
    EXPECT_FALSE(ErrorOf([&] { mem.Allocate("tooBig", g2 + 1, Space::kInternal); }).empty()) << at;
    // g2 bits skip the smaller first gap; then g1 bits fill the first gap exactly.
    const Allocation x = mem.Allocate("x", g2, Space::kInternal);
    EXPECT_EQ(x.address, d.address) << at;
    const Allocation y = mem.Allocate("y", g1, Space::kInternal);
    EXPECT_EQ(y.address, b.address) << at;
    EXPECT_EQ(mem.Used(Space::kInternal), cap) << at;
    // Without a space a request that no internal gap holds goes external.
    EXPECT_EQ(mem.Allocate("spill", 1).space, Space::kExternal) << at;
    for (const Allocation& z : {a, c, e, x, y}) mem.Free(z.id);
    EXPECT_EQ(mem.Allocate("all", cap, Space::kInternal).address, 0) << at;
  }
}

// The allocator's gaps (bitserial/memory.h) against first fit computed the plain way, by
// walking the live variables in address order: 20 000 random allocations and frees of mixed
// sizes in both spaces give every address, every refusal and every used count the same.
TEST(BitserialMemory, GapsGiveTheAddressesOfAPlainFirstFit) {
  PeMemory mem(2048, 8192, 1);
  struct Live {
    int id;
    Space space;
    int64_t address, bits;
  };
  std::vector<Live> live;  // the reference: every live variable
  auto plainFirstFit = [&](Space s, int64_t bits, int64_t capacity) -> std::optional<int64_t> {
    std::vector<std::pair<int64_t, int64_t>> taken;
    for (const Live& l : live)
      if (l.space == s) taken.push_back({l.address, l.bits});
    std::sort(taken.begin(), taken.end());
    int64_t next = 0;
    for (const auto& [address, size] : taken) {
      if (address - next >= bits) return next;
      next = address + size;
    }
    if (capacity - next >= bits) return next;
    return std::nullopt;
  };
  uint64_t state = 12345;
  auto random = [&](uint64_t n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return (state >> 33) % n;
  };
  for (int step = 0; step < 20000; ++step) {
    if (!live.empty() && random(100) < 45) {
      const size_t k = random(live.size());
      mem.Free(live[k].id);
      live.erase(live.begin() + long(k));
    } else {
      const Space s = random(2) ? Space::kInternal : Space::kExternal;
      const int64_t bits = 1 + int64_t(random(random(4) == 0 ? 900 : 40));
      const auto want = plainFirstFit(s, bits, mem.Capacity(s));
      if (!want) {
        EXPECT_THROW(mem.Allocate("v", bits, s), UserError) << step;
        continue;
      }
      const Allocation a = mem.Allocate("v", bits, s);
      ASSERT_EQ(a.address, *want) << "step " << step;
      live.push_back({a.id, s, a.address, bits});
    }
    int64_t used[2] = {0, 0};
    for (const Live& l : live) used[int(l.space)] += l.bits;
    ASSERT_EQ(mem.Used(Space::kInternal), used[0]) << step;
    ASSERT_EQ(mem.Used(Space::kExternal), used[1]) << step;
  }
  EXPECT_EQ(mem.Live().size(), live.size());
}

TEST(BitserialMemory, VirtualLayersSplitTheMemory) {
  Machine m(Profile("wavetracer"), 384 * 384);
  EXPECT_EQ(m.Layers(), 18);
  EXPECT_EQ(m.WordsPerPlane(), 18u * 128u);
  EXPECT_EQ(m.Memory().Capacity(Space::kInternal), 2048 / 18);
  EXPECT_EQ(m.Memory().Capacity(Space::kExternal), 32 * 1024 * 8 / 18);
  // Exactly filling a virtual PE's internal share works through the Multi layer...
  Multi big(m, Format::Signed(100, 0), "big", Space::kInternal);
  Multi rest(m, Format::Unsigned(2048 / 18 - 101, 0), "rest", Space::kInternal);
  EXPECT_EQ(m.Memory().Used(Space::kInternal), 2048 / 18);
  // ...one bit more fails, naming the variable; without a space it goes external.
  std::string e = ErrorOf([&] { Multi x(m, Format::Unsigned(1, 0), "oneMore", Space::kInternal); });
  EXPECT_NE(e.find("'oneMore'"), std::string::npos) << e;
  EXPECT_NE(e.find("18 virtual-PE layers"), std::string::npos) << e;
  Multi spill(m, Format::Unsigned(1, 0), "spill");
  EXPECT_EQ(spill.GetSpace(), Space::kExternal);
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
