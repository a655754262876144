// hosts/simd_ops.h — the two array routines the primary pass needs that bitserial/multi.h
// does not offer yet: square root and division, as restoring (one result bit per step)
// loops over bit-planes, charged step by step with bitserial/'s own subtract and select
// schedules (one "sqrt"/"div" entry in the cycle report).
//
// When bitserial/ gains Sqrt and Div these should be replaced by them (the results are the
// same: fixed::Sqrt's floor of the exact root; floor of the exact quotient).
#pragma once

#include "bitserial/multi.h"

namespace zephyr::simd {

// floor(sqrt(a)) in `out` (like fixed::Sqrt); 0 where a < 0 (no flag). `out` must have at
// least ceil(a's integer bits / 2) integer bits (checked), so the root always fits.
bitserial::Multi SqrtFloor(const bitserial::Multi& a, fixed::Format out);

// floor(num / den) in `out`, for num >= 0 and den > 0 (the magnitudes of the planes are
// used: a negative num or den gives a meaningless value that callers mask off). A quotient
// past `out`'s range saturates and sets the PE's overflow flag where active; den == 0 is such
// an overflow.
bitserial::Multi DivPositive(const bitserial::Multi& num, const bitserial::Multi& den,
                             fixed::Format out);

// Runs `body` with overflow flags it raises discarded: for clamps whose saturation means
// "no hit" rather than an error (charged as two flag operations: save and restore).
template <typename F>
void WithExpectedSaturation(bitserial::Machine& m, F&& body);

}  // namespace zephyr::simd

// ---- implementation of the template ----
#include <vector>
namespace zephyr::simd {
template <typename F>
void WithExpectedSaturation(bitserial::Machine& m, F&& body) {
  const size_t words = m.WordsPerPlane();
  std::vector<bitserial::Word> saved(m.OverflowPlane(), m.OverflowPlane() + words);
  body();
  std::copy(saved.begin(), saved.end(), m.OverflowPlane());
  bitserial::MicroOpCounts c;
  c.Add(bitserial::MicroOp::FlagOp, 2);
  m.Charge("saturateClamp", c);
}
}  // namespace zephyr::simd
