// bitserial/reductions.cpp — MultiC's reductions over the whole array (bitserial/multi.h):
// Any, ReduceOr/And/Xor, ReduceMax/Min, ReduceSum, each charged by its schedule (cost.h) and
// combining every layer.
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

// ---- reductions -----------------------------------------------------------------------------

namespace {
// A reduction combines every layer: a layer block holds only some (bitserial/blocks.h).
void CheckWhole(const Machine& m, const char* what) {
  if (m.IsBlock())
    throw UserError(
        fmt::format("{} reduces over every virtual-PE layer; a machine holding only "
                    "layers {}..{} of {} cannot run it (run reductions on the whole "
                    "machine, not in layer blocks)",
                    what, m.FirstLayer(), m.FirstLayer() + m.Layers() - 1, m.ModelledLayers()));
}

bool AnyActive(const Machine& m, const Word* plane, bool complement) {
  const Word* act = m.Activity();
  for (size_t w = 0; w < m.WordsPerPlane(); ++w)
    if ((complement ? ~plane[w] : plane[w]) & act[w]) return true;
  return false;
}

fixed::Fixed Bitwise(const Multi& a, ReduceKind kind) {
  Machine& m = a.GetMachine();
  CheckWhole(m, ReduceName(kind));
  m.Charge(ReduceName(kind), ReduceCost(kind, a.AsOperand()));
  fixed::BigInt bits = 0;
  for (int i = 0; i < a.Width(); ++i) {
    bool bit = false;
    if (kind == ReduceKind::kOr) bit = AnyActive(m, a.Plane(i), false);
    if (kind == ReduceKind::kAnd) bit = !AnyActive(m, a.Plane(i), true);
    if (kind == ReduceKind::kXor) {
      int64_t n = 0;
      for (size_t w = 0; w < m.WordsPerPlane(); ++w)
        n += std::popcount(a.Plane(i)[w] & m.Activity()[w]);
      bit = n & 1;
    }
    if (bit) boost::multiprecision::bit_set(bits, i);
  }
  return fixed::Fixed::FromBits(a.Format(), bits);
}

fixed::Fixed Extreme(const Multi& a, bool isMax) {
  Machine& m = a.GetMachine();
  CheckWhole(m, ReduceName(isMax ? ReduceKind::kMax : ReduceKind::kMin));
  m.Charge(ReduceName(isMax ? ReduceKind::kMax : ReduceKind::kMin),
           ReduceCost(isMax ? ReduceKind::kMax : ReduceKind::kMin, a.AsOperand()));
  const Format& f = a.Format();
  if (!AnyActive(m, m.OnesPlane(), false)) return fixed::Fixed{f, isMax ? f.MinRaw() : f.MaxRaw()};
  const size_t words = m.WordsPerPlane();
  std::vector<Word> cand(m.Activity(), m.Activity() + words);
  fixed::BigInt bits = 0;
  for (int i = a.Width() - 1; i >= 0; --i) {
    const Word* plane = a.Plane(i);
    // The bit value the extreme prefers: 1 for max, 0 for min; inverted for a sign bit.
    bool want = isMax != (f.isSigned && i == a.Width() - 1);
    bool found = false;
    for (size_t w = 0; w < words && !found; ++w) found = (want ? plane[w] : ~plane[w]) & cand[w];
    bool bit = found ? want : !want;
    for (size_t w = 0; w < words; ++w) cand[w] &= bit ? plane[w] : ~plane[w];
    if (bit) boost::multiprecision::bit_set(bits, i);
  }
  return fixed::Fixed::FromBits(f, bits);
}
}  // namespace

fixed::Fixed ReduceOr(const Multi& a) { return Bitwise(a, ReduceKind::kOr); }
fixed::Fixed ReduceAnd(const Multi& a) { return Bitwise(a, ReduceKind::kAnd); }
fixed::Fixed ReduceXor(const Multi& a) { return Bitwise(a, ReduceKind::kXor); }
bool Any(const Multi& mask) {
  CheckBool(mask, "Any");
  return ReduceOr(mask).raw != 0;
}

fixed::Fixed ReduceSum(const Multi& a) {
  Machine& m = a.GetMachine();
  CheckWhole(m, "reduceSum");
  m.Charge("reduceSum", ReduceCost(ReduceKind::kSum, a.AsOperand()));
  fixed::BigInt sum = 0;
  for (int i = 0; i < a.Width(); ++i) {
    int64_t n = 0;
    for (size_t w = 0; w < m.WordsPerPlane(); ++w)
      n += std::popcount(a.Plane(i)[w] & m.Activity()[w]);
    fixed::BigInt term = fixed::BigInt(n) << i;
    if (a.Format().isSigned && i == a.Width() - 1)
      sum -= term;
    else
      sum += term;
  }
  int extra = 0;
  while ((int64_t{1} << extra) < m.ModelledPes()) ++extra;
  Format f{a.Format().isSigned, a.Format().intBits + extra, a.Format().fracBits};
  return fixed::Fixed{f, sum};
}

fixed::Fixed ReduceMax(const Multi& a) { return Extreme(a, true); }
fixed::Fixed ReduceMin(const Multi& a) { return Extreme(a, false); }

}  // namespace zephyr::bitserial
