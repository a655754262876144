// The worked example of docs/programming.md (tools/examples/life.h): Conway's Life on the
// emulated array equals the plain C++ version, generation by generation, on a 384x384 grid
// of 18 virtual-PE layers; a glider crosses the layers' boundaries intact; the cycles of a
// generation do not depend on the cells.
#include "tools/examples/life.h"

#include <gtest/gtest.h>

#include <random>

namespace zephyr::examples {
namespace {

using bitserial::Machine;
using bitserial::MeshShape;
using bitserial::Multi;

std::vector<int64_t> Cells(const Multi& m) {
  std::vector<int64_t> v(m.GetMachine().VirtualPes());
  for (int64_t pe = 0; pe < static_cast<int64_t>(v.size()); ++pe) v[pe] = m.BitAt(0, pe);
  return v;
}

TEST(ToolsLife, EqualsThePlainVersionOn384x384) {
  Machine m(bitserial::Profile("wavetracer"), 384 * 384);
  ASSERT_EQ(m.Layers(), 18);
  const MeshShape grid{{384, 384}};
  std::mt19937_64 rng(3);
  std::vector<int64_t> plain(m.VirtualPes());
  for (auto& c : plain) c = rng() % 3 == 0;
  Multi alive(m, fixed::Format::Unsigned(1, 0), "alive");
  alive.LoadRaw(plain);
  double cycles = -1;
  for (int g = 0; g < 6; ++g) {
    const double before = m.Report().TotalCycles();
    alive = LifeStep(alive, grid);
    const double step = m.Report().TotalCycles() - before;
    if (cycles < 0) cycles = step;
    EXPECT_EQ(step, cycles) << "generation " << g;  // the same instructions every generation
    plain = LifeStepPlain(plain, 384, 384);
    ASSERT_EQ(Cells(alive), plain) << "generation " << g;
  }
}

TEST(ToolsLife, AGliderCrossesTheLayers) {
  // A glider moves (+1, +1) every 4 generations; started at (120, 15) it crosses x = 128
  // and the storage layers' boundaries (8192 PEs = 21.3 rows of 384) within 40 generations.
  Machine m(bitserial::Profile("wavetracer"), 384 * 384);
  const MeshShape grid{{384, 384}};
  std::vector<int64_t> plain(m.VirtualPes(), 0);
  for (auto [x, y] : {std::pair{1, 0}, {2, 1}, {0, 2}, {1, 2}, {2, 2}})
    plain[120 + x + 384 * (15 + y)] = 1;
  Multi alive(m, fixed::Format::Unsigned(1, 0), "alive");
  alive.LoadRaw(plain);
  const std::vector<int64_t> start = plain;
  for (int g = 0; g < 40; ++g) alive = LifeStep(alive, grid);
  std::vector<int64_t> moved(plain.size(), 0);
  for (int64_t v = 0; v < static_cast<int64_t>(start.size()); ++v)
    if (start[v]) moved[v + 10 + 384 * 10] = 1;
  EXPECT_EQ(Cells(alive), moved);
}

}  // namespace
}  // namespace zephyr::examples
