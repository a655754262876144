// tests/bitserial/closed_forms.h — each operation's micro-op counts as closed forms in the
// operand width, written from docs/bitserial.md ("The schedules"), not from bitserial/cost.cpp's
// loops: the tests compare what the engine charges, micro-op by micro-op, with these.
//
// Families (n = operand width, signed operands s(n-1-f).f with f = kFrac fraction bits):
//  * add, sub, neg, abs, min, max, select, convert/shift, compare: out has n bits and
//    `drop` fewer fraction bits (lo = drop; a shift by s gives lo = drop - s);
//  * mul, square: the product's 2f fraction bits, out n bits with lo = drop (n >= 8);
//  * mulUni: an s7.0 constant with `ones` one bits, out n bits with lo = drop (n >= 8);
//  * div: n-bit signed integers into the same format; sqrt: an n-bit signed integer into
//    out of `outWidth` bits (n or floor(n/2) - 1);
//  * reductions and mesh shifts over n bits.
// Spaces: `sa`, `sb` the operands', `so` the result's (reads and writes cost by space).
//
// Floating point (namespace fp, docs/float.md "The bit-serial schedule" and "Closed forms"):
// every float operation's micro-op counts for any format eXmY (ftz or not), pass by pass in
// the order of the doc's steps, with the operands in either memory or uni, the result in
// either memory.
#pragma once

#include <bit>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>

#include "bitserial/cost.h"
#include "fixed/float.h"
#include "fixed/format.h"

namespace zephyr::bitserial::closed {

inline constexpr int kFrac = 3;

// Micro-op name (as in the report's "microOps") → count per layer.
struct Counts {
  std::map<std::string, int64_t> n;
  Counts& Add(const std::string& op, int64_t k) {
    if (k) n[op] += k;
    return *this;
  }
  Counts& operator+=(const Counts& o) {
    for (auto& [op, k] : o.n) Add(op, k);
    return *this;
  }
};

inline std::string R(Space s) { return s == Space::kInternal ? "readInternal" : "readExternal"; }
inline std::string W(Space s) { return s == Space::kInternal ? "writeInternal" : "writeExternal"; }

inline bool Nearest(fixed::Policy p) { return p.rounding == fixed::Rounding::kNearest; }
inline bool Saturate(fixed::Policy p) { return p.overflow == fixed::OverflowPolicy::kSaturate; }

// The two extra passes over a wo-bit result: Nearest (lo > 0) `flag + wo·(r + alu + w) + alu`,
// Saturate (when overflow is possible) `flag + wo·(r + alu + w)`.
inline Counts RoundPass(Space so, int wo) {
  return Counts{}.Add("flagOp", 1).Add(R(so), wo).Add("aluStep", wo + 1).Add(W(so), wo);
}
inline Counts SaturatePass(Space so, int wo) {
  return Counts{}.Add("flagOp", 1).Add(R(so), wo).Add("aluStep", wo).Add(W(so), wo);
}
inline Counts Extras(fixed::Policy p, bool rounds, bool canOverflow, Space so, int wo) {
  Counts c;
  if (Nearest(p) && rounds) c += RoundPass(so, wo);
  if (Saturate(p) && canOverflow) c += SaturatePass(so, wo);
  return c;
}

inline fixed::Format Operand(int n) { return fixed::Format::Signed(n - 1 - kFrac, kFrac); }
// n bits with `frac` fraction bits.
inline fixed::Format Out(int n, int frac) { return fixed::Format::Signed(n - 1 - frac, frac); }

// add / sub (one carry flag): the exact sum has n+1 bits, so it can overflow n bits only
// while lo <= 1 (lo = 1 needs Nearest's carry).
inline Counts AddSub(int n, int drop, fixed::Policy p, Space sa, Space sb, Space so) {
  const bool rounds = Nearest(p) && drop > 0, ovf = 1 + rounds > drop;
  Counts c;
  c.Add(R(sa), n).Add(R(sb), n).Add("aluStep", n + drop + ovf).Add(W(so), n).Add("flagOp", 1);
  return c += Extras(p, drop > 0, ovf, so, n);
}
inline Counts Neg(int n, int drop, fixed::Policy p, Space sa, Space so) {
  const bool rounds = Nearest(p) && drop > 0, ovf = 1 + rounds > drop;
  Counts c;
  c.Add(R(sa), n).Add("aluStep", n + drop + ovf).Add(W(so), n).Add("flagOp", 1);
  return c += Extras(p, drop > 0, ovf, so, n);
}
// abs: as neg without the carry flag, plus the sign read and two flags (the negate mask).
inline Counts Abs(int n, int drop, fixed::Policy p, Space sa, Space so) {
  const bool rounds = Nearest(p) && drop > 0, ovf = 1 + rounds > drop;
  Counts c;
  c.Add(R(sa), n + 1).Add("aluStep", n + drop + ovf).Add(W(so), n).Add("flagOp", 2);
  return c += Extras(p, drop > 0, ovf, so, n);
}
// compare: flag + (n+1)·alu + 2n·r + w.
inline Counts Compare(int n, Space sa, Space sb, Space so) {
  return Counts{}.Add("flagOp", 1).Add(R(sa), n).Add(R(sb), n).Add("aluStep", n + 1).Add(W(so), 1);
}
// min / max: the compare without its write, a flag, and the select pass over the union
// format (n bits: its result never overflows out, which has `drop` more integer bits).
inline Counts MinMax(int n, int drop, fixed::Policy p, Space sa, Space sb, Space so) {
  Counts c;
  c.Add("flagOp", 2)
      .Add(R(sa), 2 * n)
      .Add(R(sb), 2 * n)
      .Add("aluStep", 2 * n + 1 + drop)
      .Add(W(so), n);
  return c += Extras(p, drop > 0, false, so, n);
}
// select(mask, a, b) with the mask in sb's space: the mask read and flag, then the pass.
inline Counts Select(int n, int drop, fixed::Policy p, Space sa, Space sb, Space so) {
  Counts c;
  c.Add(R(sb), 1 + n).Add(R(sa), n).Add("flagOp", 1).Add("aluStep", n + drop).Add(W(so), n);
  return c += Extras(p, drop > 0, false, so, n);
}
// a·2^s into out (lo = drop - s): n reads, n + max(lo, 0) alu, n writes (zero-filled low
// bits when lo < 0, which is also exactly when the result can overflow).
inline Counts Shift(int n, int drop, int s, fixed::Policy p, Space sa, Space so) {
  const int lo = drop - s;
  Counts c;
  c.Add(R(sa), n).Add("aluStep", n + std::max(lo, 0)).Add(W(so), n);
  return c += Extras(p, lo > 0, lo < 0, so, n);
}
// n×n multiply into n bits with lo = drop (1 <= ... < n): per multiplier bit r + flag +
// n·(r + alu + accR + accW); n writes; `drop` high bits leave the accumulator (accR); the
// n - drop bits above the output feed the overflow latch (accR + alu).
inline Counts Mul(int n, int drop, fixed::Policy p, Space sa, Space sb, Space so, bool square) {
  const int above = std::max(n - drop, 1);
  Counts c;
  c.Add(R(square ? sa : sb), n).Add("flagOp", n).Add(R(sa), int64_t(n) * n);
  c.Add("aluStep", int64_t(n) * n + above).Add("accumulatorRead", int64_t(n) * n + drop + above);
  c.Add("accumulatorWrite", int64_t(n) * n).Add(W(so), n);
  return c += Extras(p, drop > 0, true, so, n);
}
inline fixed::Format MulOut(int n, int drop) { return Out(n, 2 * kFrac - drop); }
// An n-bit multi × an s7.0 constant with `ones` one bits, into n bits with lo = drop.
inline Counts MulUni(int n, int ones, int drop, fixed::Policy p, Space sa, Space so) {
  Counts c;
  c.Add("flagOp", ones).Add(R(sa), int64_t(ones) * n).Add("aluStep", int64_t(ones) * n + 8 - drop);
  c.Add("accumulatorRead", int64_t(ones) * n + n).Add("accumulatorWrite", int64_t(ones) * n);
  c.Add(W(so), n);
  return c += Extras(p, drop > 0, true, so, n);
}
inline fixed::Format MulUniOut(int n, int drop) { return Out(n, kFrac - drop); }

// Restoring division of n-bit signed integers into the same format. Nearest computes one
// more quotient bit (m = n + 1 steps). Magnitudes 2·(r + flag + n·(r + alu + w)); b == 0:
// n·(r + alu) + flag; per step 2·flag + (n + [dividend bit]) internal reads + 2n·(accR + accW)
// + (n+1)·alu + a quotient-bit write; the floor correction; the (m+1)-bit quotient's
// aligned pass; the b == 0 replacement.
inline Counts Div(int n, fixed::Policy p, Space sa, Space sb, Space so) {
  const int N = Nearest(p), m = n + N;
  Counts c;
  c.Add(R(sa), 1 + n + 1 + 1).Add(R(sb), 1 + n + n + 1);
  c.Add("flagOp", 2 + 1 + 2 * m + 2 + 1);
  c.Add("aluStep", 3 * n + int64_t(m) * (n + 1) + (n + 1 + m + 1) + (n + N + 1));
  c.Add("writeInternal", 2 * n + m + (m + 1));
  c.Add("readInternal", int64_t(m) * n + n + m + (n + N + 1));
  c.Add("accumulatorRead", 2 * int64_t(n) * m + n).Add("accumulatorWrite", 2 * int64_t(n) * m);
  c.Add(W(so), 2 * n);
  return c += Extras(p, N, true, so, n);
}
// Restoring square root of an n-bit signed integer into `outWidth` signed integer bits
// (h = floor(n/2) root bits; rounding ignored; overflow possible when outWidth < h).
inline Counts Sqrt(int n, int outWidth, fixed::Policy p, Space sa, Space so) {
  const int64_t h = n / 2, tri = h * (h - 1) / 2;
  Counts c;
  c.Add("flagOp", 2 * h + 2).Add(R(sa), n).Add("accumulatorRead", h * h + 2 * h - 1);
  c.Add("readInternal", tri + h).Add("writeInternal", h);
  c.Add("aluStep", tri + 3 * h + std::max<int64_t>(outWidth, h))
      .Add("accumulatorWrite", 2 * tri + 4 * h);
  c.Add(W(so), 2 * outWidth);
  if (Saturate(p) && outWidth < h) c += SaturatePass(so, outWidth);
  return c;
}
// Reductions over n bits: n·(r + reduceBit); max/min add activitySet + n·(alu + broadcastBit).
inline Counts Reduce(int n, bool extreme, Space sa) {
  Counts c;
  c.Add(R(sa), n).Add("reduceBit", n);
  if (extreme) c.Add("activitySet", 1).Add("aluStep", n).Add("broadcastBit", n);
  return c;
}
// A mesh shift by d: n·(r + |d|·meshHop + w).
inline Counts MeshShift(int n, int d, Space s) {
  return Counts{}.Add(R(s), n).Add("meshHop", int64_t(n) * std::abs(d)).Add(W(s), n);
}

// ---------------------------------------------------------------------------------------
// Floating point. A pass costs, per plane it touches, what reading or writing that plane
// costs where the plane lives (docs/float.md, "The bit-serial schedule"):
enum class At {
  kInternal,  // PE memory: readInternal / writeInternal
  kExternal,  // readExternal / writeExternal
  kAcc,       // the working significand: accumulatorRead / accumulatorWrite
  kFlag,      // a PE flag register: loading it is a flagOp, the ALU reads it for free
  kConst,     // a constant or a uni's bit, supplied by the controller: free to read
};
inline At Of(Space s) { return s == Space::kInternal ? At::kInternal : At::kExternal; }

namespace fp {

// Counts with a plane's place deciding the micro-op.
struct Tally {
  Counts c;
  Tally& Rd(At a, int64_t k = 1) {
    if (a == At::kInternal) c.Add("readInternal", k);
    if (a == At::kExternal) c.Add("readExternal", k);
    if (a == At::kAcc) c.Add("accumulatorRead", k);
    return *this;
  }
  Tally& Wr(At a, int64_t k = 1) {
    if (a == At::kInternal) c.Add("writeInternal", k);
    if (a == At::kExternal) c.Add("writeExternal", k);
    if (a == At::kAcc) c.Add("accumulatorWrite", k);
    if (a == At::kFlag) c.Add("flagOp", k);
    return *this;
  }
  Tally& Alu(int64_t k = 1) { return c.Add("aluStep", k), *this; }
  Tally& Flag(int64_t k = 1) { return c.Add("flagOp", k), *this; }
  // A boolean of one or two planes (read where they live) into a plane at `out`.
  Tally& Logic(std::initializer_list<At> in, At out = At::kFlag) {
    for (At a : in) Rd(a);
    return Alu().Wr(out);
  }
  // k such booleans of flag registers into flag registers.
  Tally& Flags(int64_t k) { return Alu(k).Flag(k); }
};

inline int CeilLog2(int64_t n) {
  int k = 0;
  while ((int64_t{1} << k) < n) ++k;
  return k;
}
// The exponent working width: a sign bit and the magnitude of every value the exponent
// passes see (the largest field sum `xrMax`, the folded constant c, the denormalising shift).
inline int ExpWidth(int64_t xrMax, int64_t c) { return CeilLog2(xrMax + std::abs(c) + 3) + 1; }
// The one bits of c in an x-bit two's complement word.
inline int OnesOf(int64_t c, int x) {
  return std::popcount(static_cast<uint64_t>(c) & ((uint64_t{1} << x) - 1));
}

// The planes of a working significand v of n planes: v[0] (the sticky bit) at v0, the
// others at vr.
struct Sig {
  int n;
  At v0, vr;
};

// One stage of a right shift by s (1 <= s < n) where a flag says so, the s bits that fall off
// ORed into the sticky bit v[0]: their OR (s reads), ANDed with the stage's mask (a read of
// the mask), ORed into v[0], then the masked move of v[1..n) (the mask read again; n-1-s
// sources exist): n reads and writes of v, n + 1 + s ALU steps, 3 flag operations.
inline void RightStage(Tally& t, const Sig& v, int64_t s, At mask) {
  t.Rd(v.v0).Rd(v.vr, v.n - 1).Wr(v.v0).Wr(v.vr, v.n - 1).Rd(mask, 2).Alu(v.n + 1 + s).Flag(3);
}
// A shift past the top (every bit of v[1..n) gone): their OR into v[0] where `all`, then
// v[1..n) cleared under it.
inline void ClearStage(Tally& t, const Sig& v) {
  t.Rd(v.vr, v.n - 1).Alu(v.n - 1).Flag();  // any bit set above the sticky bit
  t.Flags(1);                               // ... and the shift is past the top
  t.Rd(v.v0).Alu().Wr(v.v0);                // into the sticky bit
  t.Flag().Alu(v.n - 1).Wr(v.vr, v.n - 1);  // v[1..n) = 0 where so
}
// A right shift of v by an `a`-bit amount (its planes at `amount`) where the flag `enable`:
// one stage per amount bit below ceil(log2 n), each masked by amount bit AND enable; the
// amount's higher bits ORed (a pass over them) into one clearing stage.
inline void ShiftRightBy(Tally& t, const Sig& v, int a, At amount) {
  const int stages = CeilLog2(v.n);
  for (int k = 0; k < std::min(stages, a); ++k) {
    t.Logic({amount});
    RightStage(t, v, int64_t{1} << k, At::kFlag);
  }
  if (a > stages) {
    t.Rd(amount, a - stages).Alu(a - stages).Flag().Flags(1);
    ClearStage(t, v);
  }
}
// One normalising stage, left by s (1 <= s < n) where the top s bits are zero: their NOR (s
// reads), the masked move (n - s sources, n writes), the stage's bit u_k (not taken) to
// internal memory: n reads and writes of v, n + 1 + s ALU steps, 2 flag operations.
inline void LeftStage(Tally& t, const Sig& v, int64_t s) {
  t.Rd(v.v0).Rd(v.vr, v.n - 1).Wr(v.v0).Wr(v.vr, v.n - 1).Alu(v.n + 1 + s).Flag(2);
  t.Wr(At::kInternal);
}
// `stages` normalising stages, 2^(stages-1) first.
inline void Normalise(Tally& t, const Sig& v, int stages) {
  for (int k = stages - 1; k >= 0; --k) LeftStage(t, v, int64_t{1} << k);
}

// Step 1 of every operation: an operand's fields. One pass over the e exponent bits (at x)
// latches "not all zero" (the hidden bit, to internal memory) and "all ones" (a flag); the
// hidden bit's complement sets a subnormal's exponent bit 0 (field 0 reads as 1: a read of
// bit 0 and a write to internal memory); flush-to-zero formats complement it once more to
// gate the fraction off (the gate rides on the passes that read the fraction). A subtrahend's
// sign is complemented into internal memory.
inline void Unpack(Tally& t, const fixed::FloatFormat& f, At x, bool negate) {
  const int e = f.expBits;
  if (negate) t.Logic({x}, At::kInternal);
  t.Rd(x, e).Alu(e).Wr(At::kInternal).Flag();  // hidden bit, all ones
  if (!f.subnormals) t.Logic({At::kInternal});
  t.Logic({At::kInternal}).Logic({x, At::kFlag}, At::kInternal);  // bit 0 |= !hidden
}
// The class flags from "fraction not zero" (latched by a pass that read the fraction, one
// flagOp counted there): NaN, inf, and zero (the hidden bit, read from internal memory, and
// with subnormals the fraction flag too).
inline void Classify(Tally& t, const fixed::FloatFormat& f) {
  t.Flags(2);
  if (f.subnormals)
    t.Logic({At::kInternal}).Flags(1);
  else
    t.Logic({At::kInternal});
}
inline void Latch(Tally& t) { t.Flag(); }  // a flag latched by a pass that reads its bits anyway

// Step 7, shared by every operation but the comparisons and ftofixed: round and pack.
// v: the significand (leading one at the top, v[0] sticky), n >= p + 2 planes; the top
// position's exponent field is xr + c, xr an x-plane serial number of which `xrRead` planes
// are in internal memory (the others constant zeros), c folded into the packing pass; the
// result's sign at `sign` (read once); the result at `out`. Every special-case flag is a flag
// register or a constant (free to read).
inline void RoundPack(Tally& t, const fixed::FloatFormat& f, const Sig& v, int x, int64_t c,
                      int xrRead, At sign, At out) {
  const int p = f.Precision(), m = f.fracBits, e = f.expBits, lsb = v.n - p;
  if (f.subnormals) {
    // t = -c - xr (x planes to internal memory); tiny where t >= 0: the field is below 1 and
    // v shifts right by 1 - field = t + 1 (t's x - 1 magnitude planes, then one more stage).
    t.Flag().Rd(At::kInternal, xrRead).Alu(x).Wr(At::kInternal, x);
    t.Logic({At::kInternal});
    ShiftRightBy(t, v, x - 1, At::kInternal);
    RightStage(t, v, 1, At::kFlag);
  }
  // Round to nearest even: sticky = OR of v[0..lsb-1); up = guard & (sticky | lsb).
  t.Rd(v.v0).Rd(v.vr, lsb - 2).Alu(lsb - 1).Flag();
  t.Logic({v.vr}).Logic({lsb - 1 == 0 ? v.v0 : v.vr});
  // The constant's one bits are "not tiny" (each a complement of the tiny flag).
  t.Flags(OnesOf(c, x));
  // The packing increment: (xr << m | v's m fraction bits) + (c << m) + up over 1 + m + x
  // positions, the fraction into the accumulator, the field into internal memory.
  t.Flag()
      .Rd(v.vr, m)
      .Rd(At::kInternal, xrRead)
      .Alu(1 + m + x)
      .Wr(At::kAcc, m)
      .Wr(At::kInternal, x);
  // field >= all ones (its sign latched along): overflow unless zero; inf.
  t.Flag().Flags(3);
  if (!f.subnormals) t.Flag().Flags(1);  // field < 1: flush to zero
  t.Flags(3);                            // special = zero | inf | NaN; the exponent's fill
  // The fraction and exponent planes: the fill under `special`, else the packed bits.
  t.Flag().Rd(At::kAcc, m).Rd(At::kInternal, e).Alu(m + e).Wr(out, m + e);
  // The sign: an operand's infinity gives its sign, else `sign`; a NaN's sign cleared.
  t.Flags(1).Flag().Rd(sign).Alu().Wr(out);
  t.Rd(out).Alu().Wr(out);
}

// fadd / fsub (docs/float.md steps 1-7); a and b at `a`, `b`, the result at `out`.
inline Counts AddSub(const fixed::FloatFormat& f, At a, At b, At out, bool subtract) {
  const int e = f.expBits, m = f.fracBits, p = f.Precision(), n = p + 3;
  const At I = At::kInternal, signB = subtract ? I : b;
  Tally t;
  Unpack(t, f, a, false), Unpack(t, f, b, subtract);  // 1.
  // 2. d = xa - xb over e + 1 positions (each exponent's bit 0 now in internal memory);
  // its sign says b is larger (swap): the larger operand's sign, signL.
  t.Flag().Rd(I, 2).Rd(a, e - 1).Rd(b, e - 1).Alu(e + 1).Wr(I, e + 1);
  t.Logic({a, signB}).Logic({I}).Logic({a}, I);
  // 3. One pass reading both significands (swap as the mask): the larger to internal memory,
  // the smaller into the accumulator above guard, round and sticky; "fraction not zero"
  // latched for each.
  t.Rd(I).Flag().Rd(a, m).Rd(b, m).Rd(I, 2).Alu(2 * p).Wr(I, p).Wr(At::kAcc, p);
  Latch(t), Classify(t, f), Latch(t), Classify(t, f);
  // 4. Align by |d|: stage k (k < min(stages, e)) masked by d_k ^ swap, then one stage of 1
  // masked by swap itself (internal memory); d's bits above the stages (read, complemented
  // under swap along) into one clearing stage.
  const Sig small{n, At::kAcc, At::kAcc};
  const int stages = CeilLog2(n);
  for (int k = 0; k < std::min(stages, e); ++k) {
    t.Logic({I, I});
    RightStage(t, small, int64_t{1} << k, At::kFlag);
  }
  RightStage(t, small, 1, I);
  if (e > stages) {
    t.Rd(I, e - stages).Alu(e - stages).Flag();
    ClearStage(t, small);
  }
  // 5. sub = sa ^ sb (internal memory); small complemented where sub (one pass); big ± small
  // over p + 5 positions (position -1 carries sub in, n the carry or the sign); a negative
  // difference (equal exponents) negated where sub & sign; the result's sign; zero = NOR of
  // the sum; the sign of an exact zero.
  t.Logic({a, signB}, I);
  t.Rd(I).Flag().Rd(At::kAcc, n).Alu(n).Wr(At::kAcc, n);
  t.Flag().Rd(I, p + 3).Rd(At::kAcc, n).Alu(n + 2).Wr(At::kAcc, n + 1);
  t.Logic({I, At::kAcc});
  t.Flag(2).Rd(At::kAcc, n + 1).Alu(n + 1).Wr(At::kAcc, n + 1);
  t.Logic({I});
  t.Rd(At::kAcc, n + 1).Alu(n + 1).Flag();
  t.Flags(1).Logic({I, I}).Flags(1).Alu().Wr(I);
  // 6. Normalise the n + 1 planes; the field xl + u + c (xl selected from both exponents inside
  // the pass that adds u).
  const Sig sum{n + 1, At::kAcc, At::kAcc};
  const int nstages = CeilLog2(n + 1);
  Normalise(t, sum, nstages);
  const int64_t c = 2 - (int64_t{1} << nstages);
  const int x = ExpWidth((int64_t{1} << e) + (int64_t{1} << nstages), c);
  t.Rd(I, 2).Rd(a, e - 1).Rd(b, e - 1).Flag().Rd(I, nstages).Alu(x).Wr(I, x);
  // The special results: NaN (either, or inf - inf: a read of sub), inf and its sign.
  t.Flags(2).Logic({I}).Flags(1).Logic({a}).Logic({signB}).Flags(2);
  // 7.
  RoundPack(t, f, sum, x, c, x, I, out);
  return t.c;
}

// fmul: the fields, the shift-and-add product of the significands (p rows of p full adders
// into the accumulator, each row's multiplier bit read into the mask register), normalise
// (1 stage, or ceil(log2 2p) with subnormals), the bits below the top p + 2 as a sticky bit,
// the exponent xa + xb then + u (the bias folded into c), the specials, round and pack.
inline Counts Mul(const fixed::FloatFormat& f, At a, At b, At out) {
  const int e = f.expBits, m = f.fracBits, p = f.Precision();
  const At I = At::kInternal;
  Tally t;
  Unpack(t, f, a, false), Unpack(t, f, b, false);
  t.Logic({a, b}, I);  // the sign
  const int64_t pp = int64_t{p} * p;
  t.Rd(b, m).Rd(I).Flag(p).Rd(a, int64_t{m} * p).Rd(I, p).Alu(pp).Rd(At::kAcc, pp).Wr(At::kAcc, pp);
  Latch(t), Classify(t, f), Latch(t), Classify(t, f);
  const int stages = f.subnormals ? CeilLog2(2 * p) : 1;
  Normalise(t, {2 * p, At::kAcc, At::kAcc}, stages);
  if (p - 2 > 0) t.Rd(At::kAcc, p - 2).Alu(p - 2).Flag();  // the sticky bit
  t.Alu().Wr(At::kAcc);
  const int64_t c = 2 - f.Bias() - (int64_t{1} << stages);
  const int x = ExpWidth((int64_t{2} << e) + (int64_t{1} << stages), c);
  t.Flag().Rd(I, 2).Rd(a, e - 1).Rd(b, e - 1).Alu(x).Wr(I, x);
  t.Flag().Rd(I, x + stages).Alu(x).Wr(I, x);
  t.Flags(5 + 2);  // NaN (NaN, inf x 0, 0 x inf), zero, inf
  RoundPack(t, f, {p + 3, At::kAcc, At::kAcc}, x, c, x, I, out);
  return t.c;
}

// A significand with its leading one on top (fdiv, fsqrt): subnormal formats copy it (p
// planes, to `to`) and normalise the copy in ceil(log2 p) stages; flush-to-zero formats use
// the operand's planes as they are (the fraction at x, the hidden bit in internal memory).
struct NormSig {
  At frac, hidden;
  int stages;
};
inline NormSig Normalised(Tally& t, const fixed::FloatFormat& f, At x, At to) {
  const int m = f.fracBits, p = f.Precision();
  if (!f.subnormals) return {x, At::kInternal, 0};
  t.Rd(x, m).Rd(At::kInternal).Alu(p).Wr(to, p);
  const int stages = CeilLog2(p);
  Normalise(t, {p, to, to}, stages);
  return {to, to, stages};
}

// fdiv: the fields; both significands normalised (a's into the accumulator, b's into internal
// memory), "fraction not zero" latched along; p + 2 restoring steps (d = p): each a
// subtraction over p + 1 positions (the partial remainder in the accumulator, the divisor's p
// bits, the dividend bit: a's top bits seed the remainder by one copy pass, its bit 0 enters
// at the first step), the quotient bit (the sign complemented, to internal memory) and the
// restore of p positions under it; the remainder's OR as the sticky bit; one normalising
// stage; the exponent xa - xb + ua - ub + un in two or three serial passes; round and pack.
inline Counts Div(const fixed::FloatFormat& f, At a, At b, At out) {
  const int e = f.expBits, m = f.fracBits, p = f.Precision();
  const At I = At::kInternal, Acc = At::kAcc;
  Tally t;
  Unpack(t, f, a, false), Unpack(t, f, b, false);
  t.Logic({a, b}, I);
  const NormSig na = Normalised(t, f, a, Acc);
  Latch(t), Classify(t, f);
  const NormSig nb = Normalised(t, f, b, I);
  Latch(t), Classify(t, f);
  t.Rd(na.frac, m - 1).Rd(na.hidden).Alu(p - 1).Wr(Acc, p - 1);  // the remainder's seed
  const int steps = p + 2;
  t.Flag(2 * steps).Rd(Acc, int64_t{3} * p * steps).Rd(nb.frac, int64_t{m} * steps);
  t.Rd(nb.hidden, steps).Alu(int64_t{2 * p + 2} * steps).Wr(Acc, int64_t{2 * p + 1} * steps);
  t.Wr(I, steps).Rd(I, steps);         // the quotient bits, written and read as the restore's mask
  t.Rd(na.frac, 2);                    // a's bit 0: the first step's dividend bit (add and restore)
  t.Rd(Acc, p).Alu(p).Flag().Wr(Acc);  // sticky: the remainder is not zero
  LeftStage(t, {p + 3, Acc, I}, 1);
  const int S = na.stages;
  const int64_t c = f.Bias() - 1;
  const int x = ExpWidth((int64_t{1} << e) + (int64_t{1} << S) + 2, c);
  t.Flag().Rd(I, 2).Rd(I).Rd(a, e - 1).Rd(I, S).Alu(x + 1).Wr(I, x);  // un + xa + un + ua
  if (S > 0) {
    t.Flag().Rd(I).Rd(b, e - 1).Rd(I, S).Alu(x).Wr(I, x);  // xb + ub
    t.Flag().Rd(I, 2 * x).Alu(x).Wr(I, x);                 // minus it
  } else {
    t.Flag().Rd(I, x).Rd(I).Rd(b, e - 1).Alu(x).Wr(I, x);  // minus xb
  }
  t.Flags(5 + 2);  // NaN (NaN, 0/0, inf/inf), zero (0/x, x/inf), inf (inf/x, x/0)
  RoundPack(t, f, {p + 3, Acc, I}, x, c, x, I, out);
  return t.c;
}

// fsqrt: the field and the normalised significand as for fdiv; Y = xa + ua (a serial add
// with subnormals); the radicand's top p + 1 planes by one masked move (the parity of Y vs
// K decides the shift by one place: each significand bit read as both sources); p + 2
// restoring steps, step j (j = 0..p+1) on j + 3 positions: 2j + 6 ALU steps, 2j + 5
// accumulator writes, j + 1 internal reads (j root bits, the new bit as the mask); the
// remainder's OR as the sticky bit; the exponent (Y >> 1, one decrement where K is odd);
// round and pack. K = bias + 2p + 1 + 2^S is odd exactly when S = 0 (flush to zero).
inline Counts Sqrt(const fixed::FloatFormat& f, At a, At out) {
  const int e = f.expBits, m = f.fracBits, p = f.Precision();
  const At I = At::kInternal, Acc = At::kAcc;
  Tally t;
  Unpack(t, f, a, false);
  const NormSig na = Normalised(t, f, a, Acc);
  Latch(t), Classify(t, f);
  const int S = na.stages;
  const int64_t K = f.Bias() + 2 * p + 1 + (int64_t{1} << S);
  const int64_t c = p + 1 + f.Bias() - (K >> 1);
  const int x = ExpWidth((int64_t{1} << e) + (int64_t{1} << S) + 2, c);
  if (S > 0) t.Flag().Rd(I).Rd(a, e - 1).Rd(I, S).Alu(x).Wr(I, x);  // Y = xa + ua
  const bool kOdd = K & 1;
  if (kOdd) t.Logic({I});  // odd = !Y_0 (a flag), else Y_0 itself
  t.Rd(kOdd ? At::kFlag : I).Flag().Rd(na.frac, 2 * m).Rd(na.hidden, 2).Alu(p + 1).Wr(Acc, p + 1);
  const int64_t nr = p + 2;  // root bits
  const int64_t accReads = 3 + 3 * (nr - 1) * nr / 2 + 4 * (nr - 1) + 2 * (p + 1);
  t.Flag(2 * nr).Rd(I, nr * (nr + 1) / 2).Alu((nr - 1) * nr + 6 * nr);
  t.Wr(Acc, (nr - 1) * nr + 5 * nr).Wr(I, nr).Rd(Acc, accReads);
  t.Rd(Acc, p + 3).Alu(p + 3).Flag().Wr(Acc);  // sticky
  int xrRead = x - 1;                          // Y's planes above bit 0
  if (kOdd) {
    t.Flag().Rd(a, e - 1).Alu(x).Wr(I, x);  // (Y >> 1) - 1 where odd
    xrRead = x;
  }
  t.Logic({a}).Flags(1).Logic({a});  // NaN (NaN or below zero), inf (+inf only)
  RoundPack(t, f, {p + 3, Acc, I}, x, c, xrRead, a, out);
  return t.c;
}

// ffromfixed: |a| into the accumulator by one conditional negation (padded below to p + 2
// places), zero latched along; normalised in ceil(log2 n) stages; the bits below the top
// p + 2 ORed into a sticky bit; round and pack with the exponent u + c.
inline Counts FromFixed(const fixed::Format& fa, At a, const fixed::FloatFormat& f, At out) {
  const int w = fa.Width(), p = f.Precision();
  const At sign = fa.isSigned ? a : At::kConst;
  Tally t;
  const int n = std::max(w, p + 2);
  t.Rd(sign).Flag(2).Rd(a, w).Alu(w).Wr(At::kAcc, w);
  Latch(t), t.Flags(1);  // zero
  const int S = CeilLog2(n);
  Normalise(t, {n, At::kAcc, At::kAcc}, S);
  int kept = n;
  if (n > p + 3) {
    t.Rd(At::kAcc, n - p - 2).Alu(n - p - 2).Flag().Wr(At::kAcc);
    kept = p + 3;
  }
  const int64_t c = w - fa.fracBits + f.Bias() - (int64_t{1} << S);
  const int x = ExpWidth((int64_t{1} << S) + 2, c);
  RoundPack(t, f, {kept, At::kAcc, At::kAcc}, x, c, S, sign, out);
  return t.c;
}

// ftofixed: the fields and classes ("fraction not zero" by its own pass); the shift R = C -
// xa (one serial subtraction from a constant, x planes), enabled unless R < 0 or the field
// is all ones; the significand (gated off for NaN) copied into the accumulator with its LSB
// at raw place wo; shifted right by R (x - 1 amount planes) with the sticky bit; the signed
// frame of wo + p + 3 bits by one conditional negation (to `out`); the fixed-point
// conversion's aligned pass from it (docs/bitserial.md: 2 bits dropped, overflow always
// possible, every frame bit read) with its rounding and saturation passes; inf and NaN
// written under a mask.
inline Counts ToFixed(const fixed::FloatFormat& f, At a, const fixed::Format& fo,
                      fixed::Policy policy, Space out) {
  const int e = f.expBits, m = f.fracBits, p = f.Precision(), wo = fo.Width();
  const At I = At::kInternal, O = Of(out);
  Tally t;
  Unpack(t, f, a, false);
  t.Rd(a, m).Alu(m).Flag();
  Classify(t, f);
  const int64_t C = wo + f.Bias() + m - fo.fracBits;
  const int x = CeilLog2(C + (int64_t{1} << e) + 2) + 1;
  t.Flag().Rd(I).Rd(a, e - 1).Alu(x).Wr(I, x);
  t.Logic({I}).Flags(1);
  const int n = wo + p + 2;
  t.Rd(a, m).Rd(I).Alu(p).Wr(At::kAcc, p);
  ShiftRightBy(t, {n, At::kAcc, At::kAcc}, x - 1, I);
  t.Rd(a).Flag(2).Rd(At::kAcc, n).Alu(n + 1).Wr(O, n + 1);
  const int W = wo + p + 3;
  t.Rd(O, W).Alu(W).Wr(O, wo);
  t.c += Extras(policy, true, true, out, wo);
  t.Flags(1).Logic({a});
  if (fo.isSigned) t.Logic({a});
  t.Flag().Alu(wo).Wr(O, wo);
  return t.c;
}

// What fcompare, fmin and fmax share: each exponent scanned (hidden bit and all ones, two
// flags; flush-to-zero formats complement the hidden bit to gate the fraction), one serial
// subtraction of the magnitudes (w - 1 bits each) into its sign flag, with equality and each
// "fraction not zero" latched along, NaN and zero per operand.
inline void Order(Tally& t, const fixed::FloatFormat& f, At a, At b) {
  const int e = f.expBits, w = f.Width();
  for (At x : {a, b}) {
    t.Rd(x, e).Alu(e).Flag(2);
    if (!f.subnormals) t.Flags(1);
  }
  t.Flag().Rd(a, w - 1).Rd(b, w - 1).Alu(w).Flag();
  Latch(t), Latch(t), Latch(t);
  t.Flags(f.subnormals ? 6 : 4);
}
enum class CompareKind { kLess, kLessEqual, kEqual };
// fcompare: the ordering, then flag logic (false for NaN, -0 = +0, the signs decide unless
// they agree: a's sign read four times, b's twice), the result bit written.
inline Counts Compare(const fixed::FloatFormat& f, At a, At b, At out, CompareKind kind) {
  Tally t;
  Order(t, f, a, b);
  t.Flags(2).Logic({a, b}).Flags(1 + 2 + 2);
  t.Logic({a, b}).Logic({a}).Logic({a}).Flags(4);
  if (kind == CompareKind::kLessEqual) t.Flags(1);
  t.Alu().Wr(out);
  return t.c;
}
// fmin / fmax: the ordering; the pick (x <= y with -0 < +0, x the result's own side: its
// sign read four times, the other's twice; a NaN operand yields the other); one pass
// selecting a's or b's w bits; one masked pass writing the canonical NaN where both are NaN.
inline Counts MinMax(const fixed::FloatFormat& f, At a, At b, At out, bool isMax) {
  const int w = f.Width();
  const At x = isMax ? b : a, y = isMax ? a : b;
  Tally t;
  Order(t, f, a, b);
  t.Flags(2);
  t.Logic({x, y}).Flags(1).Logic({x}).Logic({x}).Flags(2).Logic({x, y}).Flags(2);
  t.Flags(2);
  t.Flag().Rd(a, w).Rd(b, w).Alu(w).Wr(out, w);
  t.Flags(1).Flag().Alu(w).Wr(out, w);
  return t.c;
}

}  // namespace fp

}  // namespace zephyr::bitserial::closed
