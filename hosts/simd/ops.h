// hosts/simd/ops.h — a helper of the primary pass on top of bitserial/multi.h: clamps whose
// saturation is expected (it means "no hit", not an error) must not raise the per-PE
// overflow flag that marks a pixel uncertain.
#pragma once

#include <algorithm>
#include <vector>

#include "bitserial/multi.h"

namespace zephyr::simd {

// Runs `body` with overflow flags it raises discarded (charged as two flag operations:
// save and restore).
template <typename F>
void WithExpectedSaturation(bitserial::Machine& m, F&& body) {
  const std::vector<bitserial::Word> saved = m.SaveOverflow();
  body();
  m.RestoreOverflow(saved);
  bitserial::MicroOpCounts c;
  c.Add(bitserial::MicroOp::FlagOp, 2);
  m.Charge("saturateClamp", c);
}

}  // namespace zephyr::simd
