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
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "bitserial/cost.h"
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

inline std::string R(Space s) { return s == Space::Internal ? "readInternal" : "readExternal"; }
inline std::string W(Space s) { return s == Space::Internal ? "writeInternal" : "writeExternal"; }

inline bool Nearest(fixed::Policy p) { return p.rounding == fixed::Rounding::Nearest; }
inline bool Saturate(fixed::Policy p) { return p.overflow == fixed::OverflowPolicy::Saturate; }

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
  c.Add("flagOp", 2).Add(R(sa), 2 * n).Add(R(sb), 2 * n).Add("aluStep", 2 * n + 1 + drop).Add(W(so), n);
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
  c.Add("aluStep", tri + 3 * h + std::max<int64_t>(outWidth, h)).Add("accumulatorWrite", 2 * tri + 4 * h);
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

}  // namespace zephyr::bitserial::closed
