// bitserial/mesh.cpp — moves across the PE mesh (bitserial/multi.h): MeshShift on the
// machine's shape and across the virtual mesh of the layers, charged by the schedule
// (cost.h) of each move.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "bitserial/internals.h"
#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::bitserial {

using fixed::Format;
using fixed::Policy;

// ---- mesh ---------------------------------------------------------------------------------------

namespace {
// dst[i] = src bits shifted: bit b of dst = bit b - s of src (0 outside [0, 64·words)),
// ANDed with mask.
void ShiftBits(const Word* src, Word* dst, int64_t words, int64_t s, const Word* mask) {
  const int64_t bits = words * 64;
  auto word = [&](int64_t bit) -> Word {  // 64 bits of src starting at `bit`
    if (bit <= -64 || bit >= bits) return 0;
    const int64_t q = bit >= 0 ? bit / 64 : -1 - ((-bit - 1) / 64);
    const int rem = static_cast<int>(bit - q * 64);
    const Word lo = (q >= 0 && q < words) ? src[q] : 0;
    const Word hi = (q + 1 >= 0 && q + 1 < words) ? src[q + 1] : 0;
    return rem == 0 ? lo : (lo >> rem) | (hi << (64 - rem));
  };
  for (int64_t w = 0; w < words; ++w) dst[w] = word(w * 64 - s) & mask[w];
}
}  // namespace

Multi MeshShift(const Multi& a, int axis, int distance) {
  Machine& m = a.GetMachine();
  const MeshShape& shape = m.Shape();
  if (axis < 0 || axis >= static_cast<int>(shape.extent.size()))
    throw UserError(fmt::format("mesh shift along axis {}: the {} mesh has {} axes", axis,
                                shape.Name(), shape.extent.size()));
  Multi r(m, a.Format(), "meshShift", Multi::Uninitialised{});
  m.Charge("meshShift", MeshShiftCost(a.AsOperand(), distance));
  int64_t stride = 1;
  for (int i = 0; i < axis; ++i) stride *= shape.extent[i];
  const Word* edge = m.MeshEdgeMask(axis, distance);
  const int64_t perLayer = static_cast<int64_t>(m.WordsPerLayer());
  for (int i = 0; i < a.Width(); ++i)
    for (int layer = 0; layer < m.Layers(); ++layer)
      ShiftBits(a.Plane(i) + layer * perLayer, r.Plane(i) + layer * perLayer, perLayer,
                stride * distance, edge + layer * perLayer);
  return r;
}

std::vector<int> VirtualBlock(const Machine& m, const MeshShape& shape) {
  const int rank = static_cast<int>(shape.extent.size());
  const MeshShape physical = rank == 1 ? MeshShape{{m.Profile().physicalPes}} : m.Shape();
  if (rank < 1 || rank > 3 || shape.Size() != m.ModelledPes())
    throw UserError(
        fmt::format("virtual shape {}: it must have 1 to 3 extents and cover the "
                    "machine's {} virtual PEs",
                    shape.Name(), m.ModelledPes()));
  if (static_cast<int>(physical.extent.size()) != rank)
    throw UserError(
        fmt::format("virtual shape {} has {} axes but the physical mesh {} has {} "
                    "(choose a machine shape of the same rank, or a 1-D shape)",
                    shape.Name(), rank, physical.Name(), physical.extent.size()));
  std::vector<int> block(rank);
  for (int i = 0; i < rank; ++i) {
    if (shape.extent[i] % physical.extent[i] != 0)
      throw UserError(
          fmt::format("virtual shape {}: extent {} is not a multiple of the "
                      "physical mesh {}'s {} (the block mapping needs whole blocks)",
                      shape.Name(), shape.extent[i], physical.Name(), physical.extent[i]));
    block[i] = shape.extent[i] / physical.extent[i];
  }
  return block;
}

Multi MeshShift(const Multi& a, const MeshShape& shape, int axis, int distance) {
  Machine& m = a.GetMachine();
  if (m.IsBlock())
    throw UserError(
        "a virtual mesh shift moves data between every virtual-PE layer; a machine "
        "holding only a block of the layers cannot run it");
  const std::vector<int> block = VirtualBlock(m, shape);
  if (axis < 0 || axis >= static_cast<int>(shape.extent.size()))
    throw UserError(fmt::format("mesh shift along axis {}: the virtual shape {} has {} axes", axis,
                                shape.Name(), shape.extent.size()));
  Multi r(m, a.Format(), "virtualShift", Multi::Uninitialised{});
  m.ChargeWhole("virtualShift",
                VirtualMeshShiftCost(a.AsOperand(), m.Layers(), block[axis], distance));
  int64_t stride = 1;
  for (int i = 0; i < axis; ++i) stride *= shape.extent[i];
  const int64_t extent = shape.extent[axis];
  const size_t words = m.WordsPerPlane();
  std::vector<Word> edge(words, 0);  // 1 where the source coordinate is inside the shape
  for (int64_t v = 0; v < m.VirtualPes(); ++v) {
    const int64_t c = (v / stride) % extent - distance;
    if (c >= 0 && c < extent) edge[v >> 6] |= Word{1} << (v & 63);
  }
  for (int i = 0; i < a.Width(); ++i)
    ShiftBits(a.Plane(i), r.Plane(i), static_cast<int64_t>(words), stride * distance, edge.data());
  return r;
}

}  // namespace zephyr::bitserial
