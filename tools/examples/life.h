// tools/examples/life.h — Conway's Game of Life as a program for the emulated Zephyr
// (docs/programming.md): one 1-bit multi cell per virtual PE of a square virtual grid,
// neighbours counted with shifts over the virtual mesh, the rule applied with uni
// comparisons. LifeStepPlain is the same generation in plain C++; the tests and the
// example program compare the two.
#pragma once

#include <cstdint>
#include <vector>

#include "bitserial/multi.h"

namespace zephyr::examples {

// One generation of `alive` (u1.0, one cell per virtual PE of `grid`, x fastest). Cells
// outside the grid are dead (the shifts bring in 0; no wrap-around).
inline bitserial::Multi LifeStep(const bitserial::Multi& alive, const bitserial::MeshShape& grid) {
  using bitserial::Multi;
  using bitserial::Uni;
  const fixed::Format count = fixed::Format::Unsigned(4, 0);  // 0 .. 9 cells
  // left + right + self along x, then the same sums of the rows above and below.
  const Multi row =
      Add(Add(MeshShift(alive, grid, 0, 1), MeshShift(alive, grid, 0, -1), count), alive, count);
  const Multi block =
      Add(Add(MeshShift(row, grid, 1, 1), MeshShift(row, grid, 1, -1), count), row, count);
  // block counts the cell itself: a cell is born with 3 neighbours (block == 3) and
  // survives with 2 or 3 (block == 3, or 4 while alive).
  const Uni three{fixed::Fixed{count, 3}}, four{fixed::Fixed{count, 4}};
  return Or(Equal(block, three), And(alive, Equal(block, four)));
}

// The same generation on a plain w x h grid of 0/1 cells (row-major, x fastest).
inline std::vector<int64_t> LifeStepPlain(const std::vector<int64_t>& alive, int w, int h) {
  std::vector<int64_t> next(alive.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if ((dx || dy) && xx >= 0 && xx < w && yy >= 0 && yy < h) n += alive[xx + w * yy] != 0;
        }
      const bool live = alive[x + w * y] != 0;
      next[x + w * y] = n == 3 || (live && n == 2);
    }
  return next;
}

}  // namespace zephyr::examples
