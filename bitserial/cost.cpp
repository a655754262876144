#include "bitserial/cost.h"

#include <algorithm>
#include <vector>

#include "fixed/check.h"

namespace zephyr::bitserial {

namespace {
MicroOp Read(Space s) {
  return s == Space::kInternal ? MicroOp::kReadInternal : MicroOp::kReadExternal;
}
MicroOp Write(Space s) {
  return s == Space::kInternal ? MicroOp::kWriteInternal : MicroOp::kWriteExternal;
}
// k reads of operand o's bits: PE memory, or free for a uni (the controller supplies them).
void AddRead(MicroOpCounts& c, const Operand& o, int64_t k = 1) {
  if (!o.uni) c.Add(Read(o.space), k);
}

// An operand laid on the exact result's bit positions: its bit 0 sits at `offset`.
struct Placed {
  Operand op;
  int offset;
  bool Has(int p) const { return p >= offset && p < offset + op.format.Width(); }
};

// The one pass shared by add, sub, neg, select, shift and convert (docs/bitserial.md):
// the serial loop runs over the exact result's positions p = 0 .. lo+wo-1 (lo = exact
// fraction bits - out fraction bits): a read for each operand bit that exists at p (a sign
// extension reuses the bit still in the input latch), one ALU step, and a write if p is an
// output position. Output bits below the exact LSB are written as zeros. Positions above
// the output (up to the exact top) are computed for the overflow latch: reads + ALU, no
// write; if the result cannot overflow there are none, else at least one.
// Nearest (when bits are dropped) adds a rounding pass over the output, Saturate a select
// pass when overflow is possible.
MicroOpCounts AlignedPass(const std::vector<Placed>& ops, const fixed::Format& exact, Operand out,
                          fixed::Policy policy) {
  MicroOpCounts c;
  const int w = exact.Width();
  const int wo = out.format.Width();
  const int lo = exact.fracBits - out.format.fracBits;
  const int top = lo + wo;  // first position above the output
  for (int p = 0; p < std::max(top, 0); ++p) {
    for (const Placed& o : ops)
      if (o.Has(p)) AddRead(c, o.op);
    c.Add(MicroOp::kAluStep);
    if (p >= lo) c.Add(Write(out.space));
  }
  if (lo < 0) c.Add(Write(out.space), std::min(-lo, wo));  // zero-filled low output bits
  const bool rounds = policy.rounding == fixed::Rounding::kNearest && lo > 0;
  const int roundedWidth = w + (rounds ? 1 : 0);
  const bool canOverflow = roundedWidth - lo > wo || (exact.isSigned && !out.format.isSigned);
  if (canOverflow) {
    const int extra = std::max(w - top, 1);
    for (int p = top; p < top + extra; ++p) {
      for (const Placed& o : ops)
        if (o.Has(p)) AddRead(c, o.op);
      c.Add(MicroOp::kAluStep);
    }
  }
  if (rounds) {  // increment the kept bits by the dropped half: one more serial pass
    c.Add(MicroOp::kFlagOp);
    c.Add(Read(out.space), wo);
    c.Add(MicroOp::kAluStep, wo + 1);
    c.Add(Write(out.space), wo);
  }
  if (canOverflow && policy.overflow == fixed::OverflowPolicy::kSaturate) {
    c.Add(MicroOp::kFlagOp);  // the overflow latch becomes the select mask
    c.Add(Read(out.space), wo);
    c.Add(MicroOp::kAluStep, wo);
    c.Add(Write(out.space), wo);
  }
  return c;
}

int Offset(const fixed::Format& exact, const fixed::Format& f) {
  return exact.fracBits - f.fracBits;
}

// Shift-and-add multiply (docs/bitserial.md, "The schedules", Multiply). `rows` lists the
// multiplier bit positions that get an add pass; `readRows` says whether the multiplier bit
// comes from PE memory (multi) or from the controller (uni).
MicroOpCounts MulPass(Operand a, int multiplierWidth, const std::vector<int>& rows, bool readRows,
                      Space rowSpace, const fixed::Format& exact, Operand out,
                      fixed::Policy policy) {
  MicroOpCounts c;
  const int wa = a.format.Width();
  const int w = exact.Width();
  const int wo = out.format.Width();
  const int lo = exact.fracBits - out.format.fracBits;
  const int top = lo + wo;
  for (int j : rows) {
    if (readRows) c.Add(Read(rowSpace));  // the multiplier bit into the mask register
    c.Add(MicroOp::kFlagOp);              // clear the carry
    c.Add(Read(a.space), wa);
    c.Add(MicroOp::kAluStep, wa);
    c.Add(MicroOp::kAccumulatorRead, wa);
    c.Add(MicroOp::kAccumulatorWrite, wa);
    (void)j;
  }
  // Each multiplier position retires the accumulator's low bit: written if it is an output
  // bit. The remaining high bits leave the accumulator afterwards.
  for (int p = 0; p < multiplierWidth; ++p)
    if (p >= lo && p < top) c.Add(Write(out.space));
  for (int p = multiplierWidth; p < std::min(w, std::max(top, 0)); ++p) {
    if (p < lo) continue;
    c.Add(MicroOp::kAccumulatorRead);
    c.Add(Write(out.space));
  }
  if (top > w) c.Add(Write(out.space), top - std::max(w, lo));  // sign extension of the product
  if (lo < 0) c.Add(Write(out.space), std::min(-lo, wo));
  const bool rounds = policy.rounding == fixed::Rounding::kNearest && lo > 0;
  const bool canOverflow =
      w + (rounds ? 1 : 0) - lo > wo || (exact.isSigned && !out.format.isSigned);
  if (canOverflow) {
    const int extra = std::max(w - top, 1);
    c.Add(MicroOp::kAccumulatorRead, extra);
    c.Add(MicroOp::kAluStep, extra);
  }
  if (rounds) {
    c.Add(MicroOp::kFlagOp);
    c.Add(Read(out.space), wo);
    c.Add(MicroOp::kAluStep, wo + 1);
    c.Add(Write(out.space), wo);
  }
  if (canOverflow && policy.overflow == fixed::OverflowPolicy::kSaturate) {
    c.Add(MicroOp::kFlagOp);
    c.Add(Read(out.space), wo);
    c.Add(MicroOp::kAluStep, wo);
    c.Add(Write(out.space), wo);
  }
  return c;
}
}  // namespace

fixed::Format SumFormat(const fixed::Format& a, const fixed::Format& b) {
  return {a.isSigned || b.isSigned, std::max(a.intBits, b.intBits) + 1,
          std::max(a.fracBits, b.fracBits)};
}
fixed::Format DiffFormat(const fixed::Format& a, const fixed::Format& b) {
  return {true, std::max(a.intBits, b.intBits) + 1, std::max(a.fracBits, b.fracBits)};
}
fixed::Format ProductFormat(const fixed::Format& a, const fixed::Format& b) {
  // Width a.Width()+b.Width() holds every product; the sign bit is one of those bits.
  bool s = a.isSigned || b.isSigned;
  return {s, a.Width() + b.Width() - (a.fracBits + b.fracBits) - (s ? 1 : 0),
          a.fracBits + b.fracBits};
}
fixed::Format NegFormat(const fixed::Format& a) { return {true, a.intBits + 1, a.fracBits}; }
fixed::Format AbsFormat(const fixed::Format& a) {
  return {a.isSigned, a.intBits + (a.isSigned ? 1 : 0), a.fracBits};
}
fixed::Format UnionFormat(const fixed::Format& a, const fixed::Format& b) {
  // An unsigned u(i) fits a signed s(i): the sign bit is not counted in intBits.
  return {a.isSigned || b.isSigned, std::max(a.intBits, b.intBits),
          std::max(a.fracBits, b.fracBits)};
}

MicroOpCounts AddCost(Operand a, Operand b, Operand out, fixed::Policy p) {
  fixed::Format e = SumFormat(a.format, b.format);
  MicroOpCounts c = AlignedPass({{a, Offset(e, a.format)}, {b, Offset(e, b.format)}}, e, out, p);
  c.Add(MicroOp::kFlagOp);  // clear the carry
  return c;
}

MicroOpCounts SubCost(Operand a, Operand b, Operand out, fixed::Policy p) {
  fixed::Format e = DiffFormat(a.format, b.format);
  MicroOpCounts c = AlignedPass({{a, Offset(e, a.format)}, {b, Offset(e, b.format)}}, e, out, p);
  c.Add(MicroOp::kFlagOp);  // set the carry (a + ~b + 1)
  return c;
}

MicroOpCounts NegCost(Operand a, Operand out, fixed::Policy p) {
  fixed::Format e = NegFormat(a.format);
  MicroOpCounts c = AlignedPass({{a, 0}}, e, out, p);
  c.Add(MicroOp::kFlagOp);
  return c;
}

MicroOpCounts AbsCost(Operand a, Operand out, fixed::Policy p) {
  fixed::Format e = AbsFormat(a.format);
  MicroOpCounts c = AlignedPass({{a, 0}}, e, out, p);
  if (a.format.isSigned) {  // the sign bit becomes the conditional-negate mask
    c.Add(Read(a.space));
    c.Add(MicroOp::kFlagOp, 2);
  }
  return c;
}

MicroOpCounts ShiftCost(Operand a, int k, Operand out, fixed::Policy p) {
  fixed::Format e{a.format.isSigned, a.format.intBits, a.format.fracBits};
  // The exact value a × 2^k has the same bits with k fewer fraction bits; negative
  // fraction or integer bit counts are folded into the placement of the operand.
  int frac = a.format.fracBits - k;
  int off = 0;
  if (frac < 0) {
    off = -frac;
    frac = 0;
  }
  e.fracBits = frac;
  e.intBits = std::max(0, a.format.Width() + off - frac - (a.format.isSigned ? 1 : 0));
  return AlignedPass({{a, off}}, e, out, p);
}

MicroOpCounts CompareCost(Operand a, Operand b, Space outSpace) {
  fixed::Format e = DiffFormat(a.format, b.format);
  std::vector<Placed> ops = {{a, Offset(e, a.format)}, {b, Offset(e, b.format)}};
  MicroOpCounts c;
  c.Add(MicroOp::kFlagOp);
  for (int p = 0; p < e.Width(); ++p) {
    for (const Placed& o : ops)
      if (o.Has(p)) AddRead(c, o.op);
    c.Add(MicroOp::kAluStep);
  }
  c.Add(Write(outSpace));
  return c;
}

MicroOpCounts SelectCost(Operand mask, Operand a, Operand b, Operand out, fixed::Policy p) {
  fixed::Format e = UnionFormat(a.format, b.format);
  MicroOpCounts c = AlignedPass({{a, Offset(e, a.format)}, {b, Offset(e, b.format)}}, e, out, p);
  c.Add(Read(mask.space));
  c.Add(MicroOp::kFlagOp);
  return c;
}

MicroOpCounts MinMaxCost(Operand a, Operand b, Operand out, fixed::Policy p) {
  fixed::Format e = DiffFormat(a.format, b.format);
  MicroOpCounts c;
  c.Add(MicroOp::kFlagOp);
  std::vector<Placed> ops = {{a, Offset(e, a.format)}, {b, Offset(e, b.format)}};
  for (int q = 0; q < e.Width(); ++q) {
    for (const Placed& o : ops)
      if (o.Has(q)) AddRead(c, o.op);
    c.Add(MicroOp::kAluStep);
  }
  fixed::Format u = UnionFormat(a.format, b.format);
  c += AlignedPass({{a, Offset(u, a.format)}, {b, Offset(u, b.format)}}, u, out, p);
  c.Add(MicroOp::kFlagOp);  // the comparison's sign becomes the select mask
  return c;
}

MicroOpCounts MulCost(Operand a, Operand b, Operand out, fixed::Policy p) {
  std::vector<int> rows;
  for (int j = 0; j < b.format.Width(); ++j) rows.push_back(j);
  return MulPass(a, b.format.Width(), rows, true, b.space, ProductFormat(a.format, b.format), out,
                 p);
}

MicroOpCounts MulUniCost(Operand a, const fixed::Fixed& k, Operand out, fixed::Policy p) {
  std::vector<int> rows;
  for (int j = 0; j < k.format.Width(); ++j)
    if (k.Bit(j)) rows.push_back(j);
  return MulPass(a, k.format.Width(), rows, false, Space::kInternal,
                 ProductFormat(a.format, k.format), out, p);
}

DivShape DivideShape(const fixed::Format& a, const fixed::Format& b, const fixed::Format& out,
                     fixed::Policy p) {
  DivShape s;
  const int nearestBit = p.rounding == fixed::Rounding::kNearest ? 1 : 0;
  s.shift = b.fracBits + out.fracBits + nearestBit - a.fracBits;
  s.dividendBits = a.Width() + std::max(s.shift, 0);
  s.divisorZeros = std::max(-s.shift, 0);
  s.divisorBits = b.Width() + s.divisorZeros;
  // A quotient bit i can be 1 only if |a| >= |b|·2^i >= 2^(divisorZeros + i).
  s.skipped = std::min(s.divisorZeros, s.dividendBits);
  s.steps = s.dividendBits - s.skipped;
  s.canBeNegative = a.isSigned || b.isSigned;
  const int frac = out.fracBits + nearestBit;
  // The floor quotient is below 2^m in magnitude: m bits, or m+1 with a sign.
  s.quotient = {s.canBeNegative, s.dividendBits - frac, frac};
  return s;
}

SqrtShape SquareRootShape(const fixed::Format& a, const fixed::Format& out) {
  SqrtShape s;
  s.shift = 2 * out.fracBits - a.fracBits;
  s.radicandBits = std::max(0, a.Width() - (a.isSigned ? 1 : 0) + s.shift);
  s.rootBits = (s.radicandBits + 1) / 2;
  return s;
}

// Restoring division (docs/bitserial.md): magnitudes into internal memory, one
// subtract-and-restore per quotient bit with the partial remainder in the accumulator,
// the floor correction for a negative quotient, the usual round-and-fit pass, and the
// divide-by-zero replacement.
MicroOpCounts DivCost(Operand a, Operand b, Operand out, fixed::Policy p) {
  const DivShape s = DivideShape(a.format, b.format, out.format, p);
  const int wa = a.format.Width(), wb = b.format.Width(), wo = out.format.Width();
  const int d = s.divisorBits;
  MicroOpCounts c;
  // |x|: the sign into a flag, then one conditional-complement pass written to memory.
  auto magnitude = [&](Operand x) {
    const int w = x.format.Width();
    c.Add(Read(x.space));
    c.Add(MicroOp::kFlagOp);
    c.Add(Read(x.space), w);
    c.Add(MicroOp::kAluStep, w);
    c.Add(MicroOp::kWriteInternal, w);
  };
  // A uni's magnitude and whether it is 0 come from the host.
  if (a.format.isSigned && !a.uni) magnitude(a);
  if (b.format.isSigned && !b.uni) magnitude(b);
  auto readA = [&](int64_t k = 1) {
    if (!a.uni) c.Add(a.format.isSigned ? MicroOp::kReadInternal : Read(a.space), k);
  };
  auto readB = [&] {
    if (!b.uni) c.Add(b.format.isSigned ? MicroOp::kReadInternal : Read(b.space));
  };
  if (!b.uni) {  // b == 0: an OR over b's bits, latched.
    c.Add(Read(b.space), wb);
    c.Add(MicroOp::kAluStep, wb);
    c.Add(MicroOp::kFlagOp);
  }
  // The skipped leading quotient bits leave the dividend's top bits as the remainder.
  readA(s.skipped);
  c.Add(MicroOp::kAccumulatorWrite, s.skipped);
  const int lowA = std::max(s.shift, 0);  // dividend bits below this are zero
  for (int i = s.steps - 1; i >= 0; --i) {
    c.Add(MicroOp::kFlagOp);  // set the carry: R' + ~D + 1
    for (int q = 0; q <= d; ++q) {
      if (q == 0) {
        if (i >= lowA) readA();  // bring down dividend bit i
      } else {
        c.Add(MicroOp::kAccumulatorRead);  // remainder bit q-1
      }
      if (q >= s.divisorZeros && q < d) readB();
      c.Add(MicroOp::kAluStep);
      if (q < d) c.Add(MicroOp::kAccumulatorWrite);  // the difference; bit d is its sign
    }
    c.Add(MicroOp::kFlagOp);               // latch the sign: the quotient bit is the write mask
    c.Add(MicroOp::kWriteInternal);        // the quotient bit
    c.Add(MicroOp::kAccumulatorRead, d);   // restore: the difference replaces the
    c.Add(MicroOp::kAccumulatorWrite, d);  // remainder where the quotient bit is 1
  }
  const int m = s.dividendBits;
  if (s.canBeNegative) {
    // floor of a negative quotient: -Q - (R != 0) = ~Q + (R == 0), where the signs differ.
    c.Add(MicroOp::kAccumulatorRead, d);
    c.Add(MicroOp::kAluStep, d);
    c.Add(MicroOp::kFlagOp);  // R == 0
    if (a.format.isSigned) AddRead(c, a);
    if (b.format.isSigned) AddRead(c, b);
    c.Add(MicroOp::kAluStep);
    c.Add(MicroOp::kFlagOp);  // the quotient's sign
    c.Add(MicroOp::kReadInternal, m);
    c.Add(MicroOp::kAluStep, m + 1);
    c.Add(MicroOp::kWriteInternal, m + 1);
  }
  c += AlignedPass({{Operand{s.quotient, Space::kInternal}, 0}}, s.quotient, out, p);
  // Where b == 0: the end of the range on a's side (written under the latched mask).
  c.Add(MicroOp::kFlagOp);
  if (a.format.isSigned) AddRead(c, a);
  c.Add(Write(out.space), wo);
  (void)wa;
  return c;
}

// Restoring square root (docs/bitserial.md): per root bit, bring down two radicand bits,
// subtract 4·root + 1 from the partial remainder (accumulator) and restore where negative.
MicroOpCounts SqrtCost(Operand a, Operand out, fixed::Policy p) {
  const SqrtShape s = SquareRootShape(a.format, out.format);
  const int wo = out.format.Width();
  const int ma = a.format.Width() - (a.format.isSigned ? 1 : 0);
  const int nr = s.rootBits;
  MicroOpCounts c;
  for (int j = 0; j < nr; ++j) {  // j root bits decided; this step finds bit i
    const int i = nr - 1 - j;
    const int n = j + 3;                           // positions of R' - (4Y + 1), sign on top
    const int remainderBits = j == 0 ? 0 : j + 1;  // R <= 2Y < 2^(j+1)
    c.Add(MicroOp::kFlagOp);
    for (int q = 0; q < n; ++q) {
      if (q < 2) {
        const int bit = 2 * i + q - s.shift;  // radicand bit 2i+q is a's bit `bit`
        if (bit >= 0 && bit < ma) c.Add(Read(a.space));
      } else if (q - 2 < remainderBits) {
        c.Add(MicroOp::kAccumulatorRead);
      }
      if (q >= 2 && q < j + 2) c.Add(MicroOp::kReadInternal);  // root bit (trial 4Y + 1)
      c.Add(MicroOp::kAluStep);
      if (q < n - 1) c.Add(MicroOp::kAccumulatorWrite);
    }
    c.Add(MicroOp::kFlagOp);
    c.Add(MicroOp::kWriteInternal);  // the root bit
    c.Add(MicroOp::kAccumulatorRead, j + 2);
    c.Add(MicroOp::kAccumulatorWrite, j + 2);
  }
  if (a.format.isSigned) {  // a < 0: the sign is the invalid mask
    c.Add(Read(a.space));
    c.Add(MicroOp::kFlagOp);
  }
  if (nr > 0) {
    const fixed::Format root{false, nr - out.format.fracBits, out.format.fracBits};
    c += AlignedPass({{Operand{root, Space::kInternal}, 0}}, root, out,
                     {fixed::Rounding::kFloor, p.overflow});
  } else {
    c.Add(Write(out.space), wo);  // the root is 0
  }
  if (a.format.isSigned) {  // zeros written where a < 0
    c.Add(MicroOp::kFlagOp);
    c.Add(Write(out.space), wo);
  }
  return c;
}

MicroOpCounts LogicCost(Operand a, bool binary, Space outSpace) {
  MicroOpCounts c;
  c.Add(Read(a.space), binary ? 2 : 1);
  c.Add(MicroOp::kAluStep);
  c.Add(Write(outSpace));
  return c;
}

MicroOpCounts CopyCost(Operand a, Operand out) {
  MicroOpCounts c;
  AddRead(c, a, a.format.Width());
  c.Add(Write(out.space), out.format.Width());
  return c;
}

MicroOpCounts BroadcastCost(Operand out) {
  MicroOpCounts c;
  c.Add(MicroOp::kBroadcastBit, out.format.Width());
  c.Add(Write(out.space), out.format.Width());
  return c;
}

MicroOpCounts HostTransferCost(int width) {
  MicroOpCounts c;
  c.Add(MicroOp::kHostPlane, width);
  return c;
}

const char* ReduceName(ReduceKind k) {
  static const char* names[] = {"reduceOr",  "reduceAnd", "reduceXor",
                                "reduceSum", "reduceMax", "reduceMin"};
  return names[static_cast<int>(k)];
}

MicroOpCounts ReduceCost(ReduceKind kind, Operand a) {
  MicroOpCounts c;
  const int w = a.format.Width();
  c.Add(Read(a.space), w);
  c.Add(MicroOp::kReduceBit, w);
  if (kind == ReduceKind::kMax || kind == ReduceKind::kMin) {
    // Most significant bit first: each answer bit is broadcast back and the PEs that
    // differ from it drop out of the candidate set.
    c.Add(MicroOp::kActivitySet);
    c.Add(MicroOp::kAluStep, w);
    c.Add(MicroOp::kBroadcastBit, w);
  }
  return c;
}

MicroOpCounts MeshShiftCost(Operand a, int distance) {
  MicroOpCounts c;
  const int w = a.format.Width();
  c.Add(Read(a.space), w);
  c.Add(MicroOp::kMeshHop, static_cast<int64_t>(w) * std::abs(distance));
  c.Add(Write(a.space), w);
  return c;
}

MicroOpCounts VirtualMeshShiftCost(Operand a, int layers, int block, int distance) {
  ZEPHYR_CHECK(block >= 1 && layers % block == 0);
  MicroOpCounts c;
  const int64_t w = a.format.Width();
  AddRead(c, a, w * layers);
  c.Add(Write(a.space), w * layers);
  // Hermite: over the block's positions i, the source PE is floor((i - d) / b) PEs away,
  // and those distances sum to |d|; layers / block layers sit at each position.
  c.Add(MicroOp::kMeshHop, w * std::abs(distance) * (layers / block));
  return c;
}

MicroOpCounts WhereCost(Operand mask) {
  MicroOpCounts c;
  c.Add(Read(mask.space));
  c.Add(MicroOp::kActivitySet);
  return c;
}

MicroOpCounts ActivityCost() {
  MicroOpCounts c;
  c.Add(MicroOp::kActivitySet);
  return c;
}

}  // namespace zephyr::bitserial
