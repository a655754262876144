// Hardware-fidelity test 5: reductions and mesh shifts equal plain scalar loops, on the
// 2D and 3D WaveTracer shapes and the MPP's, with more than one virtual-PE layer.
#include <gtest/gtest.h>

#include <random>

#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;

TEST(BitserialComm, ReductionsMatchScalarLoops) {
  std::mt19937_64 rng(4);
  Machine m(Profile("wavetracer"), 3 * 8192 - 100);  // the last 100 PEs do not exist
  const Format f = Format::Signed(6, 3);
  std::vector<int64_t> raw(m.VirtualPes()), maskRaw(m.VirtualPes());
  for (auto& x : raw) x = static_cast<int64_t>(rng() % 1024) - 512;
  for (auto& x : maskRaw) x = (rng() % 5) != 0;
  Multi x(m, f, "x"), mask(m, BoolFormat(), "mask");
  x.LoadRaw(raw);
  mask.LoadRaw(maskRaw);
  WhereScope scope(mask);
  int64_t sum = 0, mx = INT64_MIN, mn = INT64_MAX;
  uint64_t orBits = 0, andBits = 0x3ff, xorBits = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (!maskRaw[i]) continue;
    sum += raw[i], mx = std::max(mx, raw[i]), mn = std::min(mn, raw[i]);
    const uint64_t bits = static_cast<uint64_t>(raw[i]) & 0x3ff;
    orBits |= bits, andBits &= bits, xorBits ^= bits;
  }
  EXPECT_EQ(ReduceSum(x).raw, sum);
  EXPECT_EQ(ReduceMax(x).raw, mx);
  EXPECT_EQ(ReduceMin(x).raw, mn);
  EXPECT_EQ(ReduceOr(x).Bits(), orBits);
  EXPECT_EQ(ReduceAnd(x).Bits(), andBits);
  EXPECT_EQ(ReduceXor(x).Bits(), xorBits);
  EXPECT_TRUE(Any(mask));
  Multi none = x < x;
  EXPECT_FALSE(Any(none));
}

void CheckShifts(const std::string& profile, int shapeIndex) {
  std::mt19937_64 rng(8);
  Machine m(Profile(profile), 2 * Profile(profile).physicalPes, shapeIndex);
  const MeshShape& shape = m.Shape();
  const Format f = Format::Unsigned(3, 0);
  std::vector<int64_t> raw(m.VirtualPes());
  for (auto& x : raw) x = static_cast<int64_t>(rng() % 8);
  Multi x(m, f, "x");
  x.LoadRaw(raw);
  const int pes = m.Profile().physicalPes;
  for (int axis = 0; axis < static_cast<int>(shape.extent.size()); ++axis)
    for (int d : {1, -1, 3, -5}) {
      Multi y = MeshShift(x, axis, d);
      std::vector<int64_t> got = y.ReadRaw();
      int stride = 1;
      for (int a = 0; a < axis; ++a) stride *= shape.extent[a];
      for (int64_t v = 0; v < m.VirtualPes(); ++v) {
        const int pe = static_cast<int>(v % pes);
        const int coord = (pe / stride) % shape.extent[axis];
        const int from = coord - d;  // the edge rule: outside the mesh gives 0
        const int64_t want =
            (from < 0 || from >= shape.extent[axis]) ? 0 : raw[v - int64_t{d} * stride];
        ASSERT_EQ(got[v], want) << shape.Name() << " axis " << axis << " d " << d << " pe " << v;
      }
    }
}

TEST(BitserialComm, MeshShiftsMatchScalarLoops2D) { CheckShifts("wavetracer", 0); }
TEST(BitserialComm, MeshShiftsMatchScalarLoops3D) { CheckShifts("wavetracer", 1); }
TEST(BitserialComm, MeshShiftsMatchScalarLoopsMpp) { CheckShifts("mpp", 0); }

TEST(BitserialComm, MeshShiftCost) {
  Machine m(Profile("wavetracer"));
  Multi x(m, Format::Signed(9, 0), "x");
  Multi y = MeshShift(x, 1, -3);
  EXPECT_EQ(m.Report().OpCycles("meshShift"), 10 * (1 + 3 + 1));
  EXPECT_THROW(MeshShift(x, 2, 1), UserError);  // the 2D shape has no third axis
}

}  // namespace
}  // namespace zephyr::bitserial
