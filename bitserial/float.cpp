#include "bitserial/float.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstring>
#include <tuple>
#include <unordered_map>

#include "bitserial/internals.h"
#include "bitserial/serial.h"
#include "fixed/check.h"

namespace zephyr::bitserial {

using fixed::FloatFormat;

namespace {

using namespace serial;  // Serial, Loc, Planes, OutPlanes (bitserial/serial.h)

OutPlanes Out(const Multi& x, int from, int to) {
  OutPlanes r;
  for (int i = from; i < to; ++i) r.push_back(const_cast<Multi&>(x).Plane(i));
  return r;
}

// Where `enable`: v >>= amount (unsigned planes, bit k worth 2^k), the bits that fall off
// ORed into the sticky bit v[0]. One stage per amount bit below log2(v.size()); an amount
// of 2^stages or more leaves only the sticky bit.
void ShiftRightStickyBy(Serial& s, const OutPlanes& v, const Planes& amount, const Word* enable) {
  const int n = static_cast<int>(v.size()), a = static_cast<int>(amount.size());
  const int stages = CeilLog2(n);
  for (int k = 0; k < std::min(stages, a); ++k)
    s.ShiftRightSticky(v, s.And(amount[k], enable), 1 << k);
  if (a > stages) {
    const Word* all = s.And(s.AnyOf(Slice(amount, stages, a)), enable);
    s.Logic(LogicOp::kOr, v[0], s.And(all, s.AnyOf(Slice(In(v), 1, n))), Loc::kAcc, v[0]);
    s.Mux(all, s.Zeros(n - 1), Slice(In(v), 1, n), OutPlanes(v.begin() + 1, v.end()));
  }
}

// Restoring division of unsigned planes, as the fixed-point divider (docs/bitserial.md):
// quotient bits q[steps-1..0] of dividend / divisor; the partial remainder (divisor.size()
// accumulator planes) starts as the dividend's top dividend.size() - steps bits (fewer than
// the divisor has). Per bit: one subtraction over d+1 positions, the quotient bit from its
// sign, and the remainder restored under it. Returns the final remainder.
Planes Divide(Serial& s, const Planes& dividend, const Planes& divisor, const OutPlanes& q) {
  const int d = static_cast<int>(divisor.size()), steps = static_cast<int>(q.size());
  const int skipped = static_cast<int>(dividend.size()) - steps;
  ZEPHYR_CHECK(skipped >= 0 && skipped <= d);
  OutPlanes r[2] = {s.New(d, Loc::kAcc), s.New(d, Loc::kAcc)};
  OutPlanes t = s.New(d + 1, Loc::kAcc);
  s.Copy(Slice(dividend, steps, steps + skipped), OutPlanes(r[0].begin(), r[0].begin() + skipped));
  const Planes divisorExt = Concat({divisor, {s.Zero()}});
  int cur = 0;
  for (int i = steps - 1; i >= 0; --i) {
    const Planes shifted = Concat({{dividend[i]}, In(r[cur])});  // 2R + dividend bit i
    s.Add(shifted, divisorExt, t, true, true);
    s.Logic(LogicOp::kNot, t[d], nullptr, Loc::kInternal, q[i]);
    s.Mux(q[i], Slice(In(t), 0, d), Slice(shifted, 0, d), r[1 - cur]);
    cur = 1 - cur;
  }
  return In(r[cur]);
}

// Restoring square root, as the fixed-point one (docs/bitserial.md): root bits
// root[nr-1..0] of the radicand (2·nr planes). With j bits Y decided, R <= 2Y < 2^(j+1):
// R' = 4R + two radicand bits, T = R' - (4Y + 1) over j+3 positions (its sign on top), the
// root bit from the sign, R restored under it. Returns the final remainder (nr+1 planes).
Planes SquareRoot(Serial& s, const Planes& radicand, const OutPlanes& root) {
  const int nr = static_cast<int>(root.size());
  ZEPHYR_CHECK(static_cast<int>(radicand.size()) == 2 * nr);
  OutPlanes r[2] = {s.New(nr + 1, Loc::kAcc), s.New(nr + 1, Loc::kAcc)};
  OutPlanes t = s.New(nr + 2, Loc::kAcc);
  int cur = 0;
  for (int j = 0; j < nr; ++j) {
    const int i = nr - 1 - j, n = j + 3;
    Planes shifted = {radicand[2 * i], radicand[2 * i + 1]};
    for (int k = 0; k < n - 2; ++k) shifted.push_back(k < j + 1 && j > 0 ? r[cur][k] : s.Zero());
    Planes trial = {s.Ones(), s.Zero()};
    for (int k = 0; k < n - 2; ++k) trial.push_back(k < j ? root[i + 1 + k] : s.Zero());
    const OutPlanes tj(t.begin(), t.begin() + n);
    s.Add(shifted, trial, tj, true, true);
    s.Logic(LogicOp::kNot, tj[n - 1], nullptr, Loc::kInternal, root[i]);
    const OutPlanes next(r[1 - cur].begin(), r[1 - cur].begin() + n - 1);
    s.Mux(root[i], Slice(In(tj), 0, n - 1), Slice(shifted, 0, n - 1), next);
    cur = 1 - cur;
  }
  return In(r[cur]);
}

// An operand split into its fields, with its class flags.
struct Unpacked {
  Planes frac;  // fracBits planes (flush-to-zero formats: 0 where the exponent field is 0)
  Planes exp;   // the effective biased exponent: a subnormal's field 0 reads as 1
  Planes sig;   // frac and the hidden bit on top: the significand, precision planes
  const Word* sign;
  const Word* hidden;
  const Word* maxField;
  const Word* zero = nullptr;  // set by Classify
  const Word* inf = nullptr;
  const Word* nan = nullptr;
};

// The fields: one pass over the exponent latches "not all zero" (the hidden bit) and
// "all ones" (inf or NaN); a subnormal's exponent bit 0 is then set (effective field 1).
Unpacked Unpack(Serial& s, const MultiFloat& x, bool negate) {
  const FloatFormat& f = x.Format();
  const int m = f.fracBits, e = f.expBits, w = f.Width();
  s.Place(x.Bits());
  Unpacked u;
  const Multi& bits = x.Bits();
  for (int i = 0; i < m; ++i) u.frac.push_back(bits.Plane(i));
  for (int i = m; i < m + e; ++i) u.exp.push_back(bits.Plane(i));
  u.sign = negate ? s.Not(bits.Plane(w - 1), Loc::kInternal) : bits.Plane(w - 1);
  std::tie(u.hidden, u.maxField) = s.AnyAll(u.exp, Loc::kInternal);
  if (!f.subnormals)  // flush to zero on input: the passes that read the fraction gate
    u.frac = s.Routed(s.Not(u.hidden), u.frac, {});  // it off where the field is 0
  u.exp[0] = s.Logic(LogicOp::kOr, u.exp[0], s.Not(u.hidden), Loc::kInternal);
  u.sig = Concat({u.frac, {u.hidden}});
  return u;
}

// The class flags, given "any fraction bit set" (latched by a pass that read the fraction).
void Classify(Serial& s, const FloatFormat& f, Unpacked& u, const Word* fracAny) {
  u.nan = s.And(u.maxField, fracAny);
  u.inf = s.AndNot(u.maxField, fracAny);
  u.zero = f.subnormals ? s.Not(s.Or(u.hidden, fracAny)) : s.Not(u.hidden);
}

// The special results, decided from the operands' classes.
struct Specials {
  const Word* zero;  // the result is ±0 (sign: the `sign` given to RoundPack)
  const Word* inf;   // the result is an infinity of sign infSign (from an operand)
  const Word* infSign;
  const Word* nan;  // the canonical NaN
};

// The exponent working width: a sign and the magnitude of every value the exponent
// passes see (the field sum xr, the offset c, the denormalising shift).
int ExpWidth(int xrMax, int c) { return CeilLog2(xrMax + std::abs(c) + 3) + 1; }

// Rounds and packs. v: the significand, its leading one at the top position (or all zero
// where sp.zero), v[0] a sticky bit. The biased exponent field of the top position is
// xr + c (xr: `x` signed planes; c: a constant folded in here, so no pass adds it).
// Subnormal formats first shift v right by 1 - (xr + c) where that is positive (the
// exponent field becomes 0); then round to nearest even by one increment of the packed
// exponent-and-fraction, which also carries a rounded-up significand into the exponent.
// A field >= the maximum gives ±inf; flush-to-zero formats give ±0 for a field < 1.
void RoundPack(Serial& s, const FloatFormat& f, const Word* sign, const Planes& xr, int c,
               OutPlanes v, const Specials& sp, MultiFloat& out) {
  const int p = f.Precision(), m = f.fracBits, e = f.expBits;
  const int x = static_cast<int>(xr.size());
  const int n = static_cast<int>(v.size());
  ZEPHYR_CHECK(n >= p + 2);
  const Word* tiny = s.Zero();
  if (f.subnormals) {
    // t = -c - xr = (the denormalising shift) - 1; tiny where t >= 0.
    OutPlanes t = s.New(x, Loc::kInternal);
    s.Add(s.Const(-c, x), xr, t, true, true);
    tiny = s.Not(t[x - 1]);
    ShiftRightStickyBy(s, v, Slice(In(t), 0, x - 1), tiny);
    s.ShiftRightSticky(v, tiny, 1);  // the "+ 1" of the shift
  }
  // Round to nearest, ties to even: up = guard & (sticky | lsb).
  const int lsb = n - p;
  const Word* sticky = s.AnyOf(Slice(In(v), 0, lsb - 1));
  const Word* up = s.And(v[lsb - 1], s.Or(sticky, v[lsb]));
  // packed = (xr << m | fraction) + (c << m) + up, the exponent terms gated off where
  // tiny (a subnormal's field is 0); the carry-in enters as position -1.
  OutPlanes packed = s.New(m + x, Loc::kInternal);
  for (int i = 0; i < m; ++i) packed[i] = s.New(Loc::kAcc);
  OutPlanes sum = {nullptr};
  sum.insert(sum.end(), packed.begin(), packed.end());
  Planes cBits = s.Const(c, x);
  for (auto& b : cBits) b = b == s.Ones() ? s.Not(tiny) : s.Zero();
  Planes xrGated = f.subnormals ? s.Routed(tiny, xr, {}) : xr;
  s.Add(Concat({{up}, Slice(In(v), lsb, lsb + m), xrGated}), Concat({{up}, s.Zeros(m), cBits}), sum,
        false, false);
  const Planes field = Slice(In(packed), m, m + x);
  // field >= maxField (the sign of field - maxField, compared as the packing pass
  // produces the field), ignoring a zero result.
  OutPlanes diff(x, nullptr);
  diff[x - 1] = s.New(Loc::kFlag);
  s.CompareAlong(field, s.Const(f.MaxField(), x), diff);
  const Word* overflow = s.AndNot(s.Not(diff[x - 1]), sp.zero);
  const Word* inf = s.Or(sp.inf, overflow);
  const Word* zero = sp.zero;
  if (!f.subnormals) {  // flush to zero: field < 1
    OutPlanes below(x, nullptr);
    below[x - 1] = s.New(Loc::kFlag);
    s.CompareAlong(field, s.Const(1, x), below);
    zero = s.Or(zero, below[x - 1]);
  }
  const Word* special = s.Or(s.Or(zero, inf), sp.nan);
  const Word* maxExp = s.Or(inf, sp.nan);
  Planes fill = Concat({s.Zeros(m - 1), {sp.nan}, Planes(e, maxExp)});
  s.Place(out.Bits());
  s.Mux(special, fill, Slice(In(packed), 0, m + e), Out(out.Bits(), 0, m + e));
  const Word* signed_ = s.AndNot(sp.inf, sp.nan);  // an operand's infinity gives its sign
  Word* outSign = out.Bits().Plane(f.Width() - 1);
  s.Mux(signed_, {sp.infSign}, {sign}, {outSign});
  s.Logic(LogicOp::kAndNot, outSign, sp.nan, Loc::kInternal, outSign);
}

void CheckPair(const MultiFloat& a, const MultiFloat& b, const char* op) {
  ZEPHYR_CHECK(!a.Empty() && !b.Empty());
  if (&a.GetMachine() != &b.GetMachine())
    throw UserError(fmt::format("{}: operands on different machines", op));
  if (a.Format() != b.Format())
    throw UserError(fmt::format("{}: operands have formats {} and {}", op, a.Format().Name(),
                                b.Format().Name()));
}

// a + b (b negated for a subtraction): align the smaller significand by the exponent
// difference, add or subtract, normalise, round.
MultiFloat AddSub(const MultiFloat& a, const MultiFloat& b, bool subtract) {
  const char* name = subtract ? "fsub" : "fadd";
  CheckPair(a, b, name);
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int e = f.expBits, p = f.Precision();
  const int n = p + 3;  // significand, guard, round and sticky positions
  Serial s(mach);
  Unpacked A = Unpack(s, a, false), B = Unpack(s, b, subtract);
  // d = xa - xb; swap where b's exponent is larger; |d| by a conditional negation.
  OutPlanes d = s.New(e + 1, Loc::kInternal);
  s.Add(Concat({A.exp, {s.Zero()}}), Concat({B.exp, {s.Zero()}}), d, true, true);
  const Word* swap = d[e];
  const Word* signL =
      s.Logic(LogicOp::kXor, A.sign, s.And(swap, s.Xor(A.sign, B.sign)), Loc::kInternal);
  // The larger-exponent significand to memory, the other into the accumulator above
  // guard, round and sticky; the same pass latches each operand's "fraction not zero".
  OutPlanes big = s.New(p, Loc::kInternal);
  OutPlanes small = s.New(n, Loc::kAcc);
  s.Swap(swap, A.sig, B.sig, big, OutPlanes(small.begin() + 3, small.end()));
  Classify(s, f, A, s.AnyOfRead(A.frac));
  Classify(s, f, B, s.AnyOfRead(B.frac));
  const int stages = CeilLog2(n);
  // Shift by |d|: by d where d >= 0, else by -d = ~d + 1 (stage masks d_k ^ swap, and
  // one more stage of 1 under swap).
  for (int k = 0; k < std::min(stages, e); ++k)
    s.ShiftRightSticky(small, s.Xor(d[k], swap), 1 << k);
  s.ShiftRightSticky(small, swap, 1);
  if (e > stages) {
    s.ChargeReads(Slice(In(d), stages, e));
    const Word* all = s.AnyOf(s.XorRouted(Slice(In(d), stages, e), swap));
    s.Logic(LogicOp::kOr, small[0], s.And(all, s.AnyOf(Slice(In(small), 1, n))), Loc::kAcc,
            small[0]);
    s.Mux(all, s.Zeros(n - 1), Slice(In(small), 1, n), OutPlanes(small.begin() + 1, small.end()));
  }
  // big ± small over n+1 positions (position n: the carry, or the sign of a difference);
  // a per-PE subtraction complements small and carries in 1 through position -1.
  const Word* sub = s.Xor(A.sign, B.sign, Loc::kInternal);
  s.XorWith(small, sub);
  OutPlanes sum = s.New(n + 1, Loc::kAcc);
  OutPlanes sumOut = {nullptr};
  sumOut.insert(sumOut.end(), sum.begin(), sum.end());
  s.Add(Concat({{sub}, s.Zeros(3), In(big), {s.Zero()}}), Concat({{sub}, In(small), {sub}}), sumOut,
        false, false);
  // Equal exponents can leave small > big: negate (exactly) and flip the sign.
  const Word* neg = s.And(sub, sum[n]);
  s.NegateWhere(In(sum), neg, sum);
  const Word* signR = s.Xor(signL, neg);
  const Word* zero = s.NoneOf(In(sum));
  // Exact zero: +0 for a difference, the operands' sign for a sum (-0 + -0 = -0).
  const Word* sign = s.Logic(LogicOp::kOr, s.AndNot(signR, zero), s.And(zero, s.AndNot(signL, sub)),
                             Loc::kInternal);
  const int nstages = CeilLog2(n + 1);
  const Planes u = s.Normalise(sum, nstages);
  // The top position's field: xl + 1 - shift = xl + u + 2 - 2^nstages, with xl (the
  // larger exponent) selected from the operands inside the same pass.
  const int c = 2 - (1 << nstages);
  const int x = ExpWidth((1 << e) + (1 << nstages), c);
  OutPlanes xr = s.New(x, Loc::kInternal);
  s.ChargeReads(Concat({A.exp, B.exp}));
  s.Add(Concat({s.Routed(swap, B.exp, A.exp), s.Zeros(x - e)}), Concat({u, s.Zeros(x - nstages)}),
        xr, false, false);
  const Word* bothNan = s.Or(A.nan, B.nan);
  const Word* infMinusInf = s.And(s.And(A.inf, B.inf), sub);
  Specials sp{zero, s.Or(A.inf, B.inf), s.Or(s.And(A.inf, A.sign), s.AndNot(B.sign, A.inf)),
              s.Or(bothNan, infMinusInf)};
  MultiFloat r(mach, f, name);
  RoundPack(s, f, sign, In(xr), c, sum, sp, r);
  mach.Charge(name, s.Counts());
  return r;
}

}  // namespace

MultiFloat WrapFloat(Multi bits, const FloatFormat& f) {
  MultiFloat r;
  r.format_ = f;
  r.bits_ = std::move(bits);
  return r;
}

MultiFloat::MultiFloat(Machine& machine, FloatFormat format, std::string name,
                       std::optional<Space> space)
    : format_(format) {
  if (!format.IsValid())
    throw UserError(fmt::format("multi float '{}': invalid format {}", name, format.Name()));
  bits_ = Multi(machine, fixed::Format::Unsigned(format.Width(), 0), name, space);
}

void MultiFloat::Load(const std::vector<uint64_t>& bits) {
  std::vector<int64_t> raw(bits.size());
  for (size_t i = 0; i < bits.size(); ++i) raw[i] = static_cast<int64_t>(bits[i] & format_.Mask());
  bits_.LoadRaw(raw);
}

std::vector<uint64_t> MultiFloat::Read() const {
  std::vector<int64_t> raw = bits_.ReadRaw();
  std::vector<uint64_t> r(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) r[i] = static_cast<uint64_t>(raw[i]) & format_.Mask();
  return r;
}

uint64_t MultiFloat::At(int64_t pe) const {
  uint64_t v = 0;
  for (int i = 0; i < format_.Width(); ++i) v |= uint64_t{bits_.BitAt(i, pe)} << i;
  return v;
}

MultiFloat Broadcast(Machine& m, const UniFloat& value) {
  fixed::Format u = fixed::Format::Unsigned(value.format.Width(), 0);
  return WrapFloat(Broadcast(m, fixed::Fixed{u, fixed::BigInt(value.bits & value.format.Mask())}),
                   value.format);
}

MultiFloat Add(const MultiFloat& a, const MultiFloat& b) { return AddSub(a, b, false); }
MultiFloat Sub(const MultiFloat& a, const MultiFloat& b) { return AddSub(a, b, true); }

MultiFloat Mul(const MultiFloat& a, const MultiFloat& b) {
  CheckPair(a, b, "fmul");
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int e = f.expBits, p = f.Precision();
  Serial s(mach);
  Unpacked A = Unpack(s, a, false), B = Unpack(s, b, false);
  const Word* sign = s.Xor(A.sign, B.sign, Loc::kInternal);
  OutPlanes prod = s.New(2 * p, Loc::kAcc);
  s.Multiply(A.sig, B.sig, prod);
  // The multiply reads every bit of both fractions: it latches "fraction not zero".
  Classify(s, f, A, s.AnyOfRead(A.frac));
  Classify(s, f, B, s.AnyOfRead(B.frac));
  // Subnormal operands can leave up to 2p-1 leading zeros; normal ones at most one.
  const int stages = f.subnormals ? CeilLog2(2 * p) : 1;
  const Planes u = s.Normalise(prod, stages);
  // Keep the top p+2 bits; the rest only as a sticky bit below them.
  OutPlanes v = {s.New(Loc::kAcc)};
  s.Logic(LogicOp::kOr, s.AnyOf(Slice(In(prod), 0, p - 2)), s.Zero(), Loc::kAcc, v[0]);
  v.insert(v.end(), prod.begin() + (p - 2), prod.end());
  // Field of the top position: xa + xb - bias + 1 - shift = xa + xb + u + 2 - bias - 2^stages.
  const int c = 2 - f.Bias() - (1 << stages);
  const int x = ExpWidth((2 << e) + (1 << stages), c);
  OutPlanes xr = s.New(x, Loc::kInternal);
  s.Add(Concat({A.exp, s.Zeros(x - e)}), Concat({B.exp, s.Zeros(x - e)}), xr, false, false);
  s.Add(In(xr), Concat({u, s.Zeros(x - stages)}), xr, false, false);
  const Word* nan = s.Or(s.Or(A.nan, B.nan), s.Or(s.And(A.inf, B.zero), s.And(A.zero, B.inf)));
  const Specials sp{s.Or(A.zero, B.zero), s.Or(A.inf, B.inf), sign, nan};
  MultiFloat r(mach, f, "fmul");
  RoundPack(s, f, sign, In(xr), c, v, sp, r);
  mach.Charge("fmul", s.Counts());
  return r;
}

namespace {

// A significand with its leading one moved to the top: subnormal formats normalise a copy
// in log2(p) stages (u: the stages not taken, so the shift is 2^stages - 1 - u); flush-to-
// zero formats already have it there (u empty).
std::pair<Planes, Planes> NormalisedSig(Serial& s, const FloatFormat& f, const Planes& sig,
                                        Loc loc) {
  if (!f.subnormals) return {sig, {}};
  OutPlanes v = s.New(static_cast<int>(sig.size()), loc);
  s.Copy(sig, v);
  const Planes u = s.Normalise(v, CeilLog2(f.Precision()));
  return {In(v), u};
}

// What comparisons and min/max need of two operands: the magnitudes (exponent and
// fraction; flush-to-zero formats read a subnormal as zero), one serial subtraction of them
// (|a| < |b| from its sign, |a| == |b| latched along), and the class flags.
struct Ordered {
  const Word* signA;
  const Word* signB;
  Planes magA, magB;
  const Word* less;
  const Word* equal;
  const Word* nanA;
  const Word* nanB;
  const Word* zeroA;
  const Word* zeroB;
};

Ordered Order(Serial& s, const MultiFloat& a, const MultiFloat& b) {
  const FloatFormat& f = a.Format();
  const int m = f.fracBits, w = f.Width();
  Ordered o;
  struct Side {
    Planes mag;
    const Word* hidden;
    const Word* maxField;
  } side[2];
  const MultiFloat* ops[2] = {&a, &b};
  for (int k = 0; k < 2; ++k) {
    const Multi& bits = ops[k]->Bits();
    s.Place(bits);
    Planes frac, exp;
    for (int i = 0; i < m; ++i) frac.push_back(bits.Plane(i));
    for (int i = m; i < w - 1; ++i) exp.push_back(bits.Plane(i));
    std::tie(side[k].hidden, side[k].maxField) = s.AnyAll(exp, Loc::kFlag);
    if (!f.subnormals) frac = s.Routed(s.Not(side[k].hidden), frac, {});
    side[k].mag = Concat({frac, exp});
  }
  o.signA = a.Bits().Plane(w - 1), o.signB = b.Bits().Plane(w - 1);
  o.magA = side[0].mag, o.magB = side[1].mag;
  OutPlanes diff(w, nullptr);
  diff[w - 1] = s.New(Loc::kFlag);
  s.Add(Concat({o.magA, {s.Zero()}}), Concat({o.magB, {s.Zero()}}), diff, true, true);
  o.less = diff[w - 1];
  o.equal = s.EqualAlong(o.magA, o.magB);
  const Word* fracAny[2] = {s.AnyOfRead(Slice(o.magA, 0, m)), s.AnyOfRead(Slice(o.magB, 0, m))};
  const Word** nan[2] = {&o.nanA, &o.nanB};
  const Word** zero[2] = {&o.zeroA, &o.zeroB};
  for (int k = 0; k < 2; ++k) {
    *nan[k] = s.And(side[k].maxField, fracAny[k]);
    *zero[k] = f.subnormals ? s.Not(s.Or(side[k].hidden, fracAny[k])) : s.Not(side[k].hidden);
  }
  return o;
}

// x ≤ y in the order of the signs and magnitudes with -0 below +0 (IEEE minimumNumber's
// order): xLess / yLess say |x| < |y| / |y| < |x|.
const Word* SignedLessEqual(Serial& s, const Word* signX, const Word* signY, const Word* xLess,
                            const Word* yLess, const Word* equal) {
  const Word* sameSign = s.Not(s.Xor(signX, signY));
  // Both negative: |x| >= |y|; both positive: |x| <= |y|.
  const Word* mag = s.Or(equal, s.Or(s.And(signX, yLess), s.AndNot(xLess, signX)));
  return s.Or(s.AndNot(signX, signY), s.And(sameSign, mag));
}

enum class CompareKind { kLess, kLessEqual, kEqual };

Multi Compare(const MultiFloat& a, const MultiFloat& b, CompareKind kind, const char* name) {
  CheckPair(a, b, name);
  Machine& mach = a.GetMachine();
  Serial s(mach);
  const Ordered o = Order(s, a, b);
  const Word* nan = s.Or(o.nanA, o.nanB);
  const Word* bothZero = s.And(o.zeroA, o.zeroB);
  const Word* sameSign = s.Not(s.Xor(o.signA, o.signB));
  const Word* greater = s.Not(s.Or(o.less, o.equal));
  // -0 == +0: two zeros are equal whatever their signs.
  const Word* eq = s.Or(bothZero, s.And(sameSign, o.equal));
  const Word* lt =
      s.AndNot(s.Or(s.AndNot(o.signA, o.signB),
                    s.And(sameSign, s.Or(s.And(o.signA, greater), s.AndNot(o.less, o.signA)))),
               bothZero);
  const Word* result = kind == CompareKind::kLess    ? lt
                       : kind == CompareKind::kEqual ? eq
                                                     : s.Or(lt, eq);
  Multi r(mach, BoolFormat(), name, Multi::Uninitialised{});
  s.Place(r);
  s.Logic(LogicOp::kAndNot, result, nan, Loc::kInternal, r.Plane(0));  // false if either is NaN
  mach.Charge("fcompare", s.Counts());
  return r;
}

// IEEE 754-2019 minimumNumber / maximumNumber (fixed::FloatMin / FloatMax).
MultiFloat MinMax(const MultiFloat& a, const MultiFloat& b, bool isMax) {
  const char* name = isMax ? "fmax" : "fmin";
  CheckPair(a, b, name);
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int w = f.Width();
  Serial s(mach);
  const Ordered o = Order(s, a, b);
  const Word* greater = s.Not(s.Or(o.less, o.equal));
  const Word* keepA = isMax ? SignedLessEqual(s, o.signB, o.signA, greater, o.less, o.equal)
                            : SignedLessEqual(s, o.signA, o.signB, o.less, greater, o.equal);
  // A NaN operand yields the other one.
  const Word* pickA = s.AndNot(s.Or(o.nanB, keepA), o.nanA);
  MultiFloat r(mach, f, name);
  s.Place(r.Bits());
  const OutPlanes out = Out(r.Bits(), 0, w);
  s.Mux(pickA, Concat({o.magA, {o.signA}}), Concat({o.magB, {o.signB}}), out);
  s.Mux(s.And(o.nanA, o.nanB), s.Const(static_cast<int64_t>(f.CanonicalNaN()), w), In(out), out);
  mach.Charge(name, s.Counts());
  return r;
}

}  // namespace

MultiFloat Div(const MultiFloat& a, const MultiFloat& b) {
  CheckPair(a, b, "fdiv");
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int e = f.expBits, p = f.Precision();
  Serial s(mach);
  Unpacked A = Unpack(s, a, false), B = Unpack(s, b, false);
  const Word* sign = s.Xor(A.sign, B.sign, Loc::kInternal);
  // Both significands with their leading one on top (the copies read every fraction bit,
  // or, flush-to-zero, the divider does: "fraction not zero" is latched along).
  const auto [na, ua] = NormalisedSig(s, f, A.sig, Loc::kAcc);
  Classify(s, f, A, s.AnyOfRead(A.frac));
  const auto [nb, ub] = NormalisedSig(s, f, B.sig, Loc::kInternal);
  Classify(s, f, B, s.AnyOfRead(B.frac));
  // q = floor(na·2^(p+1) / nb) in [2^p, 2^(p+2)): p+2 quotient bits, the remainder sticky.
  OutPlanes q = s.New(p + 2, Loc::kInternal);
  const Planes rem = Divide(s, Concat({s.Zeros(p + 1), na}), nb, q);
  OutPlanes v = {const_cast<Word*>(s.AnyOf(rem, Loc::kAcc))};
  v.insert(v.end(), q.begin(), q.end());
  const Planes un = s.Normalise(v, 1);
  // Field of the top position: xa - xb + ua - ub + un + bias - 1 (ua, ub: the operands'
  // stages not taken; the bias is folded into the packing pass).
  const int S = static_cast<int>(ua.size());
  const int c = f.Bias() - 1;
  const int x = ExpWidth((1 << e) + (1 << S) + 2, c);
  OutPlanes xr = s.New(x, Loc::kInternal);
  OutPlanes sum = {nullptr};
  sum.insert(sum.end(), xr.begin(), xr.end());
  s.Add(Concat({un, A.exp, s.Zeros(x - e)}), Concat({un, ua, s.Zeros(x - S)}), sum, false, false);
  if (S > 0) {
    OutPlanes yb = s.New(x, Loc::kInternal);
    s.Add(Concat({B.exp, s.Zeros(x - e)}), Concat({ub, s.Zeros(x - S)}), yb, false, false);
    s.Add(In(xr), In(yb), xr, true, true);
  } else {
    s.Add(In(xr), Concat({B.exp, s.Zeros(x - e)}), xr, true, true);
  }
  const Word* nan = s.Or(s.Or(A.nan, B.nan), s.Or(s.And(A.zero, B.zero), s.And(A.inf, B.inf)));
  const Specials sp{s.Or(A.zero, B.inf), s.Or(A.inf, B.zero), sign, nan};
  MultiFloat r(mach, f, "fdiv");
  RoundPack(s, f, sign, In(xr), c, v, sp, r);
  mach.Charge("fdiv", s.Counts());
  return r;
}

MultiFloat Sqrt(const MultiFloat& a) {
  ZEPHYR_CHECK(!a.Empty());
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int e = f.expBits, p = f.Precision();
  Serial s(mach);
  Unpacked A = Unpack(s, a, false);
  const auto [na, ua] = NormalisedSig(s, f, A.sig, Loc::kAcc);
  Classify(s, f, A, s.AnyOfRead(A.frac));
  const int S = static_cast<int>(ua.size());
  // a = na·2^E with E = xa + ua - bias - p + 2 - 2^S. The radicand na·2^j, j = p+3 or
  // p+4 (whichever makes E - j even), lies in [2^(2p+2), 2^(2p+4)): p+2 root bits, the
  // top one always set. With K = bias + 2p + 1 + 2^S and Y = xa + ua, j = p+4 where Y
  // and K differ in parity, and (E - j)/2 = (Y >> 1) - (K >> 1) - (K odd and j = p+4).
  const int K = f.Bias() + 2 * p + 1 + (1 << S);
  const int x = ExpWidth((1 << e) + (1 << S) + 2, p + 1 + f.Bias() - (K >> 1));
  Planes y = Concat({A.exp, s.Zeros(x - e)});
  if (S > 0) {
    OutPlanes sum = s.New(x, Loc::kInternal);
    s.Add(y, Concat({ua, s.Zeros(x - S)}), sum, false, false);
    y = In(sum);
  }
  const Word* odd = (K & 1) ? s.Not(y[0]) : y[0];  // j = p + 4
  Planes low(p + 1), high(p + 1);
  for (int i = p + 3; i < 2 * p + 4; ++i) {
    low[i - p - 3] = i - p - 3 < p ? na[i - p - 3] : s.Zero();
    high[i - p - 3] = i - p - 4 >= 0 ? na[i - p - 4] : s.Zero();
  }
  OutPlanes top = s.New(p + 1, Loc::kAcc);
  s.Mux(odd, high, low, top);
  OutPlanes root = s.New(p + 2, Loc::kInternal);
  const Planes rem = SquareRoot(s, Concat({s.Zeros(p + 3), In(top)}), root);
  OutPlanes v = {const_cast<Word*>(s.AnyOf(rem, Loc::kAcc))};
  v.insert(v.end(), root.begin(), root.end());
  // Field of the top position: p + 1 + bias + (E - j)/2.
  const int c = p + 1 + f.Bias() - (K >> 1);
  Planes xr = Concat({Slice(y, 1, x), {s.Zero()}});
  if (K & 1) {
    OutPlanes dec = s.New(x, Loc::kInternal);
    s.Add(xr, Planes(x, odd), dec, false, false);  // - odd: all ones is -1
    xr = In(dec);
  }
  const Word* nan = s.Or(A.nan, s.AndNot(A.sign, A.zero));  // NaN, or below zero
  const Specials sp{A.zero, s.AndNot(A.inf, A.sign), A.sign, nan};
  MultiFloat r(mach, f, "fsqrt");
  RoundPack(s, f, A.sign, xr, c, v, sp, r);
  mach.Charge("fsqrt", s.Counts());
  return r;
}

Multi Less(const MultiFloat& a, const MultiFloat& b) {
  return Compare(a, b, CompareKind::kLess, "fless");
}
Multi LessEqual(const MultiFloat& a, const MultiFloat& b) {
  return Compare(a, b, CompareKind::kLessEqual, "flessEqual");
}
Multi Equal(const MultiFloat& a, const MultiFloat& b) {
  return Compare(a, b, CompareKind::kEqual, "fequal");
}
MultiFloat Min(const MultiFloat& a, const MultiFloat& b) { return MinMax(a, b, false); }
MultiFloat Max(const MultiFloat& a, const MultiFloat& b) { return MinMax(a, b, true); }

MultiFloat ToFloat(const Multi& a, const FloatFormat& f) {
  ZEPHYR_CHECK(!a.Empty());
  if (!f.IsValid()) throw UserError(fmt::format("ffromfixed: invalid float format {}", f.Name()));
  Machine& mach = a.GetMachine();
  const fixed::Format& fa = a.Format();
  const int w = a.Width(), p = f.Precision();
  Serial s(mach);
  s.Place(a);
  Planes bits;
  for (int i = 0; i < w; ++i) bits.push_back(a.Plane(i));
  const Word* sign = fa.isSigned ? a.Plane(w - 1) : s.Zero();
  // |a| (w bits hold it, also for the most negative value), padded below to p+2 places.
  const int pad = std::max(0, p + 2 - w), n = w + pad;
  OutPlanes v = s.New(n, Loc::kAcc);
  const OutPlanes mag(v.begin() + pad, v.end());
  s.NegateWhere(bits, sign, mag);
  const Word* zero = s.Not(s.AnyOfRead(bits));
  const int S = CeilLog2(n);
  const Planes u = s.Normalise(v, S);
  // Keep the top p+2 bits and the rest as a sticky bit below them.
  OutPlanes kept = v;
  if (n > p + 3) {
    kept = {const_cast<Word*>(s.AnyOf(Slice(In(v), 0, n - p - 2), Loc::kAcc))};
    kept.insert(kept.end(), v.end() - (p + 2), v.end());
  }
  // The top position is worth 2^(w - 1 - fracBits - shift), shift = 2^S - 1 - u: its
  // field is u + w - fracBits + bias - 2^S.
  const int c = w - fa.fracBits + f.Bias() - (1 << S);
  const int x = ExpWidth((1 << S) + 2, c);
  const Specials sp{zero, s.Zero(), s.Zero(), s.Zero()};
  MultiFloat r(mach, f, "ffromfixed");
  RoundPack(s, f, sign, Concat({u, s.Zeros(x - S)}), c, kept, sp, r);
  mach.Charge("ffromfixed", s.Counts());
  return r;
}

Multi ToFixed(const MultiFloat& a, fixed::Format out, fixed::Policy policy) {
  ZEPHYR_CHECK(!a.Empty());
  Machine& mach = a.GetMachine();
  const FloatFormat& f = a.Format();
  const int e = f.expBits, p = f.Precision(), wo = out.Width(), fo = out.fracBits;
  // The exact value in raw units of `out`, two places below (round and sticky), up to
  // the top clamp: wo + p + 3 bits with the sign.
  const fixed::Format frameFormat = fixed::Format::Signed(wo + p - fo, fo + 2);
  if (!out.IsValid() || !frameFormat.IsValid())
    throw UserError(fmt::format("ftofixed: {} into {}: the conversion needs {} + {} + 3 <= {} bits",
                                f.Name(), out.Name(), wo, p, fixed::kMaxWidth));
  Serial s(mach);
  Unpacked A = Unpack(s, a, false);
  Classify(s, f, A, s.AnyOf(A.frac));
  // R = wo - t, t = xa - bias - m + fo the weight of the significand's LSB in raw units:
  // the significand is loaded with its LSB at raw place wo and shifted right by R.
  // R < 0 (a value 2^wo raw units or more, whose low raw bits are zero) and ±inf keep the
  // load position, which overflows every wo-bit format.
  const int C = wo + f.Bias() + f.fracBits - fo;
  const int x = CeilLog2(C + (1 << e) + 2) + 1;
  OutPlanes amount = s.New(x, Loc::kInternal);
  s.Add(s.Const(C, x), Concat({A.exp, s.Zeros(x - e)}), amount, true, true);
  const Word* shift = s.Not(s.Or(amount[x - 1], A.maxField));
  const int n = wo + p + 2;
  OutPlanes frame = s.New(n, Loc::kAcc);
  s.Copy(s.Routed(A.nan, A.sig, {}), OutPlanes(frame.begin() + wo + 2, frame.end()));  // NaN: 0
  ShiftRightStickyBy(s, frame, Slice(In(amount), 0, x - 1), shift);
  Multi exact(mach, frameFormat, "ftofixed", Multi::Uninitialised{});
  s.Place(exact);
  s.NegateWhere(Concat({In(frame), {s.Zero()}}), A.sign, Out(exact, 0, n + 1));
  Multi r(mach, out, "ftofixed", Multi::Uninitialised{});
  s.Place(r);
  s.Charge(ShiftCost(exact.AsOperand(), 0, r.AsOperand(), policy));
  ConvertUncharged(exact, r, policy);
  // ±inf: out's largest / smallest value whatever the overflow policy; NaN: 0.
  const Word* special = s.Or(A.inf, A.nan);
  const Word* low = s.AndNot(A.inf, A.sign);
  Planes fill(wo, low);
  if (out.isSigned) fill[wo - 1] = s.And(A.inf, A.sign);
  s.Mux(special, fill, In(Out(r, 0, wo)), Out(r, 0, wo));
  SetInvalid(mach, A.nan);
  mach.Charge("ftofixed", s.Counts());
  return r;
}

namespace {
MultiFloat Constant(Machine& m, const UniFloat& u) {
  return WrapFloat(Multi::Constant(m, fixed::Fixed{fixed::Format::Unsigned(u.format.Width(), 0),
                                                   fixed::BigInt(u.bits & u.format.Mask())}),
                   u.format);
}
}  // namespace

#define ZEPHYR_FLOAT_UNI(Result, Op)                                                               \
  Result Op(const MultiFloat& a, const UniFloat& b) { return Op(a, Constant(a.GetMachine(), b)); } \
  Result Op(const UniFloat& a, const MultiFloat& b) { return Op(Constant(b.GetMachine(), a), b); }
ZEPHYR_FLOAT_UNI(MultiFloat, Add)
ZEPHYR_FLOAT_UNI(MultiFloat, Sub)
ZEPHYR_FLOAT_UNI(MultiFloat, Mul)
ZEPHYR_FLOAT_UNI(MultiFloat, Div)
ZEPHYR_FLOAT_UNI(MultiFloat, Min)
ZEPHYR_FLOAT_UNI(MultiFloat, Max)
ZEPHYR_FLOAT_UNI(Multi, Less)
ZEPHYR_FLOAT_UNI(Multi, LessEqual)
ZEPHYR_FLOAT_UNI(Multi, Equal)
#undef ZEPHYR_FLOAT_UNI

const std::vector<std::string>& FloatOpNames() {
  static const std::vector<std::string> names = {"fadd",     "fsub",      "fmul", "fdiv",
                                                 "fsqrt",    "fmin",      "fmax", "fcompare",
                                                 "ftofixed", "ffromfixed"};
  return names;
}

double FloatOpCycles(const MachineProfile& profile, const std::string& op, const FloatFormat& f,
                     Space space, fixed::Format fixedSide, fixed::Policy policy) {
  return FloatOpReport(profile, op, f, space, fixedSide, policy).OpCycles(op);
}

CycleReport FloatOpReport(const MachineProfile& profile, const std::string& op,
                          const FloatFormat& f, Space space, fixed::Format fixedSide,
                          fixed::Policy policy) {
  Machine m(profile);
  MultiFloat a(m, f, "a", space), b(m, f, "b", space);
  Multi x(m, fixedSide, "x", space);
  m.Report().Clear();
  if (op == "fadd")
    Add(a, b);
  else if (op == "fsub")
    Sub(a, b);
  else if (op == "fmul")
    Mul(a, b);
  else if (op == "fdiv")
    Div(a, b);
  else if (op == "fsqrt")
    Sqrt(a);
  else if (op == "fmin")
    Min(a, b);
  else if (op == "fmax")
    Max(a, b);
  else if (op == "fcompare")
    Less(a, b);
  else if (op == "ftofixed")
    ToFixed(a, fixedSide, policy);
  else if (op == "ffromfixed")
    ToFloat(x, f);
  else
    throw UserError(
        fmt::format("unknown float operation '{}' ({})", op, fmt::join(FloatOpNames(), ", ")));
  return m.Report();
}

}  // namespace zephyr::bitserial
