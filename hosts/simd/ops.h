// hosts/simd/ops.h — array helpers of the primary pass on top of bitserial/multi.h, shared by
// the primitives' programs (hosts/simd/{sphere,ellipsoid,polygon,cone}.cpp). Clamps whose
// saturation is expected (it means "no hit", not an error) must not raise the per-PE
// overflow flag that marks a pixel uncertain.
#pragma once

#include "bitserial/multi.h"

namespace zephyr::simd {

// Floor rounding, saturation at the format's ends.
inline const fixed::Policy kSaturate{fixed::Rounding::kFloor, fixed::OverflowPolicy::kSaturate};

// Runs `body` with overflow flags it raises discarded (charged as two flag operations:
// save and restore).
template <typename F>
void WithExpectedSaturation(bitserial::Machine& m, F&& body) {
  const std::vector<bitserial::Word> saved = m.SaveOverflow();
  body();
  m.RestoreOverflow(saved);
  bitserial::MicroOpCounts c;
  c.Add(bitserial::MicroOp::kFlagOp, 2);
  m.Charge("saturateClamp", c);
}

// c·d for uni constants c, in `out`.
bitserial::Multi Dot3(const bitserial::Multi (&d)[3], const fixed::Fixed (&c)[3],
                      fixed::Format out);

// The 1-bit constant 0 in every PE.
bitserial::Multi Zero(bitserial::Machine& m);

// |x| < band (band a host constant, `frac` fraction bits), with the clamp's saturation expected.
bitserial::Multi Near(bitserial::Machine& m, const bitserial::Multi& x, double band, int frac);

// |x| < band per PE (an unsigned multi with `frac` fraction bits), the clamp's saturation expected.
bitserial::Multi Near(bitserial::Machine& m, const bitserial::Multi& x,
                      const bitserial::Multi& band, int frac);

// x − c, saturating at the format's ends (a bound, not a value that must be exact); the
// format's least value where c is not finite.
bitserial::Multi SubBound(bitserial::Machine& m, const bitserial::Multi& x, double c,
                          fixed::Format out);

// |f × d|² with each cross component (format `cross`) clamped to `clamped` first: only a
// component below the radius can hit, so saturation there means a miss, not an error.
bitserial::Multi CrossSquared(bitserial::Machine& m, const bitserial::Multi (&d)[3],
                              const fixed::Fixed (&f)[3], fixed::Format cross,
                              fixed::Format clamped, fixed::Format square);

// Σ x_k² in f (each square and the sums rounded into f).
bitserial::Multi SumOfSquares(const bitserial::Multi (&x)[3], fixed::Format f);

// |x| in an unsigned format one integer bit wider (exact).
bitserial::Multi AbsOf(const bitserial::Multi& x);

}  // namespace zephyr::simd
