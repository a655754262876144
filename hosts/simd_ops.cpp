#include "hosts/simd_ops.h"

#include <algorithm>
#include <cstring>

#include "fixed/check.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::MicroOpCounts;
using bitserial::Multi;
using bitserial::Operand;
using bitserial::Space;
using bitserial::Word;
using fixed::Format;

namespace {

// Scratch planes from the machine's pool, returned on scope exit.
struct Planes {
  Planes(Machine& m, int n) : m(m), n(std::max(n, 1)), p(m.AcquirePlanes(this->n)) {}
  ~Planes() { m.ReleasePlanes(p, n); }
  Word* operator[](int i) const { return p + size_t(i) * m.WordsPerPlane(); }
  Machine& m;
  int n;
  Word* p;
};

// diff = a - b over max(|a|,|b|)+1 bits (a, b unsigned plane lists); returns the sign plane.
const Word* SubtractInto(Machine& m, const std::vector<const Word*>& a,
                         const std::vector<const Word*>& b, const Planes& diff) {
  const int w = int(std::max(a.size(), b.size())) + 1;
  std::vector<const Word*> pa(w), pb(w);
  std::vector<Word*> po(w);
  for (int i = 0; i < w; ++i) {
    pa[i] = i < int(a.size()) ? a[i] : m.ZeroPlane();
    pb[i] = i < int(b.size()) ? b[i] : m.ZeroPlane();
    po[i] = diff[i];
  }
  bitserial::AddArgs args{pa.data(), pb.data(), po.data(), w, true, true, 0, false, nullptr, nullptr};
  m.Kernels().add(args, m.WordsPerPlane());
  return diff[w - 1];
}

// The cycles of one restoring step: a trial subtraction and a select of the remainder.
MicroOpCounts StepCost(int remBits, int subtrahendBits) {
  const Format r = Format::Unsigned(std::max(remBits, 1), 0);
  const Format s = Format::Unsigned(std::max(subtrahendBits, 1), 0);
  const Format d = Format::Signed(std::max(remBits, subtrahendBits), 0);
  MicroOpCounts c = bitserial::SubCost({r, Space::Internal}, {s, Space::Internal},
                                       {d, Space::Internal}, {});
  c += bitserial::SelectCost({bitserial::BoolFormat(), Space::Internal}, {r, Space::Internal},
                             {d, Space::Internal}, {r, Space::Internal}, {});
  return c;
}

// The magnitude planes of x (its sign plane dropped).
int MagnitudeBits(const Multi& x) { return x.Width() - (x.Format().isSigned ? 1 : 0); }

}  // namespace

Multi SqrtFloor(const Multi& a, Format outFormat) {
  Machine& m = a.GetMachine();
  const Format& fa = a.Format();
  ZEPHYR_CHECK_GE(outFormat.intBits, (fa.intBits + 1) / 2);
  Multi out(m, outFormat, "sqrt");
  // N = raw(a) × 2^(2·fo − fa) is an integer whose floor root is the result's raw value.
  const int shift = 2 * outFormat.fracBits - fa.fracBits;
  const int wm = MagnitudeBits(a);
  const int nb = wm + shift;
  if (nb <= 0) return out;
  const int nr = (nb + 1) / 2;
  auto nBit = [&](int j) -> const Word* {
    const int q = j - shift;
    return q >= 0 && q < wm ? a.Plane(q) : m.ZeroPlane();
  };
  Planes root(m, nr), remA(m, nr + 4), remB(m, nr + 4), diff(m, nr + 6);
  std::vector<const Word*> rem, next, trial;
  MicroOpCounts cost;
  const Planes* buffers[2] = {&remA, &remB};
  for (int i = nr - 1, step = 0; i >= 0; --i, ++step) {
    next = {nBit(2 * i), nBit(2 * i + 1)};
    next.insert(next.end(), rem.begin(), rem.end());
    trial = {m.OnesPlane(), m.ZeroPlane()};
    for (int k = i + 1; k < nr; ++k) trial.push_back(root[k]);
    const Word* sign = SubtractInto(m, next, trial, diff);
    m.Kernels().logic(bitserial::LogicOp::Not, sign, nullptr, root[i], m.WordsPerPlane());
    cost += StepCost(int(next.size()), int(trial.size()));
    // The remainder is below 2·root + 1: (bits decided) + 2 planes hold it.
    const int keep = std::min<int>(int(next.size()), (nr - i) + 2);
    const Planes& buf = *buffers[step & 1];
    std::vector<const Word*> pd(keep);
    std::vector<Word*> po(keep);
    for (int k = 0; k < keep; ++k) pd[k] = diff[k], po[k] = buf[k];
    m.Kernels().select(sign, next.data(), pd.data(), po.data(), keep, m.WordsPerPlane());
    rem.assign(po.begin(), po.end());
  }
  const int wo = out.Width();
  for (int k = 0; k < wo; ++k) {
    const Word* bit = k < nr ? root[k] : m.ZeroPlane();
    if (fa.isSigned)  // a < 0: the result is 0, as fixed::Sqrt gives
      m.Kernels().logic(bitserial::LogicOp::AndNot, bit, a.Plane(a.Width() - 1), out.Plane(k),
                        m.WordsPerPlane());
    else
      std::memcpy(out.Plane(k), bit, sizeof(Word) * m.WordsPerPlane());
  }
  cost += bitserial::CopyCost({Format::Unsigned(nr, 0), Space::Internal}, out.AsOperand());
  m.Charge("sqrt", cost);
  return out;
}

Multi DivPositive(const Multi& num, const Multi& den, Format outFormat) {
  Machine& m = num.GetMachine();
  Multi out(m, outFormat, "quotient");
  // value(q) = raw(num)·2^(fd − fn) / raw(den): shift whichever side keeps integers.
  const int shift = outFormat.fracBits + den.Format().fracBits - num.Format().fracBits;
  std::vector<const Word*> dividend, divisor;
  for (int i = 0; i < std::max(shift, 0); ++i) dividend.push_back(m.ZeroPlane());
  for (int i = 0; i < MagnitudeBits(num); ++i) dividend.push_back(num.Plane(i));
  for (int i = 0; i < std::max(-shift, 0); ++i) divisor.push_back(m.ZeroPlane());
  for (int i = 0; i < MagnitudeBits(den); ++i) divisor.push_back(den.Plane(i));
  const int nd = int(dividend.size());
  const int nq = MagnitudeBits(out);
  const size_t words = m.WordsPerPlane();
  Planes rem(m, nd + 1), diff(m, std::max<int>(nd, int(divisor.size())) + 2), q(m, nq),
      flags(m, 2);
  for (int i = 0; i < nd; ++i) std::memcpy(rem[i], dividend[i], sizeof(Word) * words);
  MicroOpCounts cost = bitserial::CopyCost(num.AsOperand(), {num.Format(), Space::Internal});
  // Overflow: the quotient needs more than nq bits (rem >= den·2^nq), or den == 0.
  Word* ovf = flags[0];
  std::memset(ovf, 0, sizeof(Word) * words);
  for (const Word* b : divisor) m.Kernels().logic(bitserial::LogicOp::Or, ovf, b, ovf, words);
  m.Kernels().logic(bitserial::LogicOp::Not, ovf, nullptr, ovf, words);  // den == 0
  if (nd > nq) {
    std::vector<const Word*> high;
    for (int i = nq; i < nd; ++i) high.push_back(rem[i]);
    const Word* sign = SubtractInto(m, high, divisor, diff);
    m.Kernels().logic(bitserial::LogicOp::Not, sign, nullptr, flags[1], words);
    m.Kernels().logic(bitserial::LogicOp::Or, ovf, flags[1], ovf, words);
    cost += StepCost(nd - nq, int(divisor.size()));
  }
  for (int k = nq - 1; k >= 0; --k) {
    std::vector<const Word*> part;
    for (int i = k; i < nd; ++i) part.push_back(rem[i]);
    if (part.empty()) part.push_back(m.ZeroPlane());
    const Word* sign = SubtractInto(m, part, divisor, diff);
    m.Kernels().logic(bitserial::LogicOp::Not, sign, nullptr, q[k], words);
    cost += StepCost(int(part.size()), int(divisor.size()));
    const int w = nd - k;
    if (w <= 0) continue;
    std::vector<const Word*> pa(w), pd(w);
    std::vector<Word*> po(w);
    for (int i = 0; i < w; ++i) pa[i] = rem[k + i], pd[i] = diff[i], po[i] = rem[k + i];
    m.Kernels().select(sign, pa.data(), pd.data(), po.data(), w, words);
  }
  // Saturate where the quotient overflowed; latch the flag where active.
  for (int k = 0; k < out.Width(); ++k) {
    const Word* bit = k < nq ? q[k] : m.ZeroPlane();
    m.Kernels().logic(bitserial::LogicOp::Or, bit, k < nq ? ovf : m.ZeroPlane(), out.Plane(k), words);
  }
  m.Kernels().logic(bitserial::LogicOp::And, ovf, m.Activity(), flags[1], words);
  m.Kernels().logic(bitserial::LogicOp::Or, m.OverflowPlane(), flags[1], m.OverflowPlane(), words);
  cost += bitserial::CopyCost({Format::Unsigned(nq, 0), Space::Internal}, out.AsOperand());
  cost.Add(bitserial::MicroOp::FlagOp, 2);
  m.Charge("div", cost);
  return out;
}

}  // namespace zephyr::simd
