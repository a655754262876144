// hosts/simd/ops.cpp — array helpers of the primary pass (hosts/simd/ops.h).
#include "hosts/simd/ops.h"

#include <algorithm>
#include <cmath>

#include "hosts/simd/bounds.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;

Multi Dot3(const Multi (&d)[3], const Fixed (&c)[3], Format out) {
  return Add(Add(Mul(d[0], Uni{c[0]}, out), Mul(d[1], Uni{c[1]}, out), out),
             Mul(d[2], Uni{c[2]}, out), out);
}

Multi Zero(Machine& m) { return Broadcast(m, Fixed{Format::Unsigned(1, 0), 0}); }

namespace {
// |x| in an unsigned format of x's integer bits (saturating, expected).
Multi AbsClamped(Machine& m, const Multi& x, int frac) {
  Multi a;
  WithExpectedSaturation(
      m, [&] { a = Abs(x, Format::Unsigned(std::max(1, x.Format().intBits), frac), kSaturate); });
  return a;
}
}  // namespace

Multi Near(Machine& m, const Multi& x, double band, int frac) {
  const Multi a = AbsClamped(m, x, frac);
  return a < Broadcast(m, Tight(band, frac));
}

Multi Near(Machine& m, const Multi& x, const Multi& band, int frac) {
  return AbsClamped(m, x, frac) < band;
}

Multi SubBound(Machine& m, const Multi& x, double c, Format out) {
  if (!std::isfinite(c)) return Broadcast(m, Fixed{out, out.MinRaw()});
  Multi r;
  WithExpectedSaturation(m,
                         [&] { r = Sub(x, Broadcast(m, Tight(c, out.fracBits)), out, kSaturate); });
  return r;
}

Multi CrossSquared(Machine& m, const Multi (&d)[3], const Fixed (&f)[3], Format cross,
                   Format clamped, Format square) {
  const Multi c[3] = {Sub(Mul(d[2], Uni{f[1]}, cross), Mul(d[1], Uni{f[2]}, cross), cross),
                      Sub(Mul(d[0], Uni{f[2]}, cross), Mul(d[2], Uni{f[0]}, cross), cross),
                      Sub(Mul(d[1], Uni{f[0]}, cross), Mul(d[0], Uni{f[1]}, cross), cross)};
  Multi sum;
  WithExpectedSaturation(m, [&] {
    Multi sq[3];
    for (int k = 0; k < 3; ++k)
      sq[k] = Square(Convert(c[k], clamped, kSaturate), square, kSaturate);
    sum = Add(Add(sq[0], sq[1], square, kSaturate), sq[2], square, kSaturate);
  });
  return sum;
}

Multi SumOfSquares(const Multi (&x)[3], Format f) {
  return Add(Add(Square(x[0], f), Square(x[1], f), f), Square(x[2], f), f);
}

Multi AbsOf(const Multi& x) {
  return Abs(x, Format::Unsigned(x.Format().intBits + 1, x.Format().fracBits));
}

}  // namespace zephyr::simd
