// The virtual mesh (multi.h, MultiC's shapes): a shift over the whole virtual solution space
// equals a plain C++ shift of the virtual grid, at 1 and 18 layers, in 1, 2 and 3 dimensions,
// on every compiled target; its charge is the block mapping's closed form.
#include <gtest/gtest.h>

#include <random>

#include "bitserial/blocks.h"
#include "bitserial/multi.h"
#include "fixed/check.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;

struct Case {
  const char* profile;
  int shapeIndex;
  MeshShape shape;
  int layers;
};

std::vector<Case> Cases() {
  return {{"wavetracer", 0, {{64, 128}}, 1},
          {"wavetracer", 0, {{384, 384}}, 18},
          {"wavetracer", 1, {{32, 64, 16}}, 4},
          {"mpp", 0, {{256, 128}}, 2},
          {"wavetracer", 0, {{8192 * 3}}, 3}};
}

// out(c) = in(c - d·e_axis), 0 outside, on the virtual grid in PE order (x fastest).
std::vector<int64_t> PlainShift(const std::vector<int64_t>& in, const MeshShape& s, int axis,
                                int d) {
  std::vector<int64_t> out(in.size(), 0);
  int64_t stride = 1;
  for (int i = 0; i < axis; ++i) stride *= s.extent[i];
  for (int64_t v = 0; v < static_cast<int64_t>(in.size()); ++v) {
    const int64_t c = (v / stride) % s.extent[axis] - d;
    if (c >= 0 && c < s.extent[axis]) out[v] = in[v - d * stride];
  }
  return out;
}

TEST(BitserialVirtualMesh, ShiftEqualsThePlainShiftOfTheVirtualGrid) {
  const Format f = Format::Unsigned(5, 0);
  testutil::ForEachTarget([&] {
    for (const Case& k : Cases()) {
      Machine m(Profile(k.profile), k.shape.Size(), k.shapeIndex);
      ASSERT_EQ(m.Layers(), k.layers) << k.shape.Name();
      std::mt19937_64 rng(k.layers);
      std::vector<int64_t> raw(m.VirtualPes());
      for (auto& x : raw) x = static_cast<int64_t>(rng() % 32);
      Multi x(m, f, "x");
      x.LoadRaw(raw);
      for (int axis = 0; axis < static_cast<int>(k.shape.extent.size()); ++axis)
        for (int d : {1, -1, 5, -13, 200}) {
          const Multi r = MeshShift(x, k.shape, axis, d);
          EXPECT_EQ(r.ReadRaw(), PlainShift(raw, k.shape, axis, d))
              << k.shape.Name() << " axis " << axis << " d " << d << " " << m.Kernels().target;
        }
    }
  });
}

TEST(BitserialVirtualMesh, PixelMovesToItsRightNeighbourAcrossLayers) {
  // A 384x384 image on 18 layers: pixel (127, 21) is virtual PE 8191, the last of layer 0
  // and at the physical mesh's right edge; (128, 21) is the first PE of layer 1.
  Machine m(Profile("wavetracer"), 384 * 384);
  std::vector<int64_t> raw(m.VirtualPes(), 0);
  raw[127 + 384 * 21] = 1;
  Multi x(m, Format::Unsigned(1, 0), "x");
  x.LoadRaw(raw);
  const Multi r = MeshShift(x, MeshShape{{384, 384}}, 0, 1);
  EXPECT_EQ(r.At(128 + 384 * 21).raw, 1);
  EXPECT_EQ(ReduceSum(r).raw, 1);
  // The per-layer shift treats each layer as its own 64x128 mesh: the pixel falls off it.
  const Multi perLayer = MeshShift(x, 0, 1);
  EXPECT_EQ(ReduceSum(perLayer).raw, 0);
}

TEST(BitserialVirtualMesh, ChargeIsTheBlockMappingsClosedForm) {
  // 384x384 on the 64x128 mesh: blocks of 6x3 virtual PEs per physical PE, 18 layers. Every
  // layer's w bits are read and written once; w·|d|·18/b bits cross the mesh (b = 6 along x,
  // 3 along y), where the per-layer shift would send w·|d|·18.
  for (auto [axis, d, block] : {std::tuple{0, 1, 6}, std::tuple{0, -7, 6}, std::tuple{1, 2, 3}}) {
    Machine m(Profile("wavetracer"), 384 * 384);
    const Format f = Format::Signed(7, 4);
    const int64_t w = f.Width();
    Multi x(m, f, "x");
    m.Report().Clear();
    MeshShift(x, MeshShape{{384, 384}}, axis, d);
    const std::map<std::string, int64_t> want = {{"readInternal", 18 * w},
                                                 {"writeInternal", 18 * w},
                                                 {"meshHop", w * std::abs(d) * 18 / block}};
    EXPECT_EQ(testutil::ChargedMicroOps(m, "virtualShift"), want) << axis << " " << d;
    const MachineProfile& p = m.Profile();
    EXPECT_DOUBLE_EQ(m.Report().OpCycles("virtualShift"),
                     18 * w * (p.Cost(MicroOp::kReadInternal) + p.Cost(MicroOp::kWriteInternal)) +
                         w * std::abs(d) * 18 / block * p.Cost(MicroOp::kMeshHop));
  }
}

TEST(BitserialVirtualMesh, RefusesShapesTheMappingCannotPlace) {
  Machine m(Profile("wavetracer"), 100 * 100);
  Multi x(m, Format::Unsigned(3, 0), "x");
  EXPECT_THROW(MeshShift(x, MeshShape{{100, 100}}, 0, 1), UserError);  // not whole blocks
  EXPECT_THROW(MeshShift(x, MeshShape{{100, 99}}, 0, 1), UserError);   // not the PE count
  Machine m2(Profile("wavetracer"), 384 * 384);
  Multi y(m2, Format::Unsigned(3, 0), "y");
  EXPECT_THROW(MeshShift(y, MeshShape{{384, 384}}, 2, 1), UserError);    // no such axis
  EXPECT_THROW(MeshShift(y, MeshShape{{48, 48, 64}}, 0, 1), UserError);  // rank 3 on a 2-D mesh
  Machine block(Profile("wavetracer"), 384 * 384, 0, LayerBlock{0, 3});
  Multi z(block, Format::Unsigned(3, 0), "z");
  EXPECT_THROW(MeshShift(z, MeshShape{{384, 384}}, 0, 1), UserError);
}

}  // namespace
}  // namespace zephyr::bitserial
