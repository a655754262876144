// bitserial/kernels.cpp — compiled once per Highway target (foreach_target.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "bitserial/kernels.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

#include "bitserial/kernels.h"
#include "hwy/aligned_allocator.h"

#include <algorithm>

HWY_BEFORE_NAMESPACE();
namespace zephyr::bitserial::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<uint64_t>;
using V = hn::Vec<D>;

// A full adder. On AVX-512 it is two vpternlog (HIGHWAY.md: Highway 1.0.3 has no general
// ternary-logic op); elsewhere the portable five-op form.
HWY_INLINE void FullAdd(V x, V y, V& carry, V& sum) {
#if HWY_TARGET <= HWY_AVX3
  sum = V{_mm512_ternarylogic_epi64(x.raw, y.raw, carry.raw, 0x96)};
  carry = V{_mm512_ternarylogic_epi64(x.raw, y.raw, carry.raw, 0xE8)};
#else
  const V xy = hn::Xor(x, y);
  sum = hn::Xor(xy, carry);
  carry = hn::OrAnd(hn::And(x, y), carry, xy);
#endif
}

// Bitwise mux: m ? a : b, written with And/AndNot (HIGHWAY.md: no IfVecThenElse on planes).
HWY_INLINE V Mux(V m, V a, V b) { return hn::Or(hn::And(m, a), hn::AndNot(m, b)); }

// The add runs kAddStrip vectors of PEs side by side (the whole bit loop per strip, the
// carries in registers): the plane pointers are read once per bit for the strip, and each
// plane is read as one longer run, which the prefetchers follow when an add streams ~100
// planes from L2/L3. The argument fields are copied into locals so the compiler keeps them
// in registers (a store through out[p] could otherwise alias them), and the bit loop is
// split at ovfFrom so the positions below it carry no overflow test.
constexpr size_t kAddStrip = 4;

// One bit position of a strip: sums[u] = a[p] + b[p] + carry[u] for U vectors at w.
template <size_t U, bool kInvert>
HWY_INLINE void AddStep(const Word* ap, const Word* bp, Word* op, V* HWY_RESTRICT carry,
                        V* HWY_RESTRICT sums) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  HWY_UNROLL(16)
  for (size_t u = 0; u < U; ++u) {
    const V x = hn::Load(d, ap + u * lanes);
    V y = hn::Load(d, bp + u * lanes);
    if (kInvert) y = hn::Not(y);
    FullAdd(x, y, carry[u], sums[u]);
  }
  if (op) {
    HWY_UNROLL(16)
    for (size_t u = 0; u < U; ++u) hn::Store(sums[u], d, op + u * lanes);
  }
}

template <size_t U, bool kInvert, bool kOvf>
HWY_NOINLINE void AddStrips(const AddArgs& g, size_t begin, size_t end) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const Word* const* const A = g.a;
  const Word* const* const B = g.b;
  Word* const* const O = g.out;
  const int n = g.n;
  const int ovfFrom = kOvf ? std::min(std::max(g.ovfFrom, 0), n) : n;
  const bool ovfSigned = g.ovfSigned;
  Word* const ovfPlane = g.ovf;
  const Word* const act = g.act;
  const V init = g.carryIn ? hn::Set(d, ~uint64_t{0}) : hn::Zero(d);
  for (size_t w = begin; w + U * lanes <= end; w += U * lanes) {
    V carry[U], sum[U];
    HWY_UNROLL(16)
    for (size_t u = 0; u < U; ++u) carry[u] = init;
    for (int p = 0; p < ovfFrom; ++p)
      AddStep<U, kInvert>(A[p] + w, B[p] + w, O[p] ? O[p] + w : nullptr, carry, sum);
    if (kOvf && ovfFrom < n) {
      V ref[U], ovf[U];
      AddStep<U, kInvert>(A[ovfFrom] + w, B[ovfFrom] + w, O[ovfFrom] ? O[ovfFrom] + w : nullptr,
                          carry, sum);
      HWY_UNROLL(16)
      for (size_t u = 0; u < U; ++u) {
        ref[u] = ovfSigned ? sum[u] : hn::Zero(d);
        ovf[u] = hn::Xor(sum[u], ref[u]);
      }
      for (int p = ovfFrom + 1; p < n; ++p) {
        AddStep<U, kInvert>(A[p] + w, B[p] + w, O[p] ? O[p] + w : nullptr, carry, sum);
        HWY_UNROLL(16)
        for (size_t u = 0; u < U; ++u) ovf[u] = hn::Or(ovf[u], hn::Xor(sum[u], ref[u]));
      }
      HWY_UNROLL(16)
      for (size_t u = 0; u < U; ++u) {
        const size_t o = w + u * lanes;
        const V old = hn::Load(d, ovfPlane + o);
        hn::Store(hn::OrAnd(old, ovf[u], hn::Load(d, act + o)), d, ovfPlane + o);
      }
    }
  }
}

template <bool kInvert, bool kOvf>
void AddRange(const AddArgs& g, size_t begin, size_t end) {
  const size_t strip = kAddStrip * hn::Lanes(D());
  const size_t mid = begin + (end - begin) / strip * strip;
  AddStrips<kAddStrip, kInvert, kOvf>(g, begin, mid);
  AddStrips<1, kInvert, kOvf>(g, mid, end);
}

void Add(const AddArgs& g, size_t words) {
  const bool ovf = g.ovf != nullptr;
  if (g.invertB) ovf ? AddRange<true, true>(g, 0, words) : AddRange<true, false>(g, 0, words);
  else ovf ? AddRange<false, true>(g, 0, words) : AddRange<false, false>(g, 0, words);
}

// One vector of PEs of roundFit; src(i) gives exact bit lo + i (i < g.k), carry the round bit.
template <class Src>
HWY_INLINE void RoundFitStrip(const RoundFitArgs& g, size_t w, V carry, const Src& src) {
  const D d;
  V ref = hn::Zero(d), ovf = hn::Zero(d), sum = hn::Zero(d);
  for (int i = 0; i < g.k; ++i) {
    const V x = src(i);
    sum = hn::Xor(x, carry);
    carry = hn::And(x, carry);
    if (i < g.wo) hn::Store(sum, d, g.out[i] + w);
    if (g.outSigned && i == g.wo - 1) ref = sum;
    if (i >= g.wo) ovf = hn::Or(ovf, hn::Xor(sum, ref));
  }
  // `sum` is now the top (sign-extension) bit of the rounded exact value.
  if (g.saturate) {
    const V neg = sum;
    for (int i = 0; i < g.wo; ++i) {
      const V sat = (g.outSigned && i == g.wo - 1) ? neg : hn::Not(neg);
      const V o = hn::Load(d, g.out[i] + w);
      hn::Store(Mux(ovf, sat, o), d, g.out[i] + w);
    }
  }
  if (g.ovf) {
    const V old = hn::Load(d, g.ovf + w);
    hn::Store(hn::OrAnd(old, ovf, hn::Load(d, g.act + w)), d, g.ovf + w);
  }
}

void RoundFit(const RoundFitArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  for (size_t w = 0; w < words; w += lanes) {
    const V carry = g.roundBit ? hn::Load(d, g.roundBit + w) : hn::Zero(d);
    RoundFitStrip(g, w, carry, [&](int i) { return hn::Load(d, g.src[i] + w); });
  }
}

// (a & m) ^ inv: a multiplier row's term, complemented for a subtracted row.
HWY_INLINE V AndXor(V a, V m, V inv) {
#if HWY_TARGET <= HWY_AVX3
  return V{_mm512_ternarylogic_epi64(a.raw, m.raw, inv.raw, 0x6A)};
#else
  return hn::Xor(hn::And(a, m), inv);
#endif
}

// Per-thread scratch for one strip of the multiply: reused, grown on demand, never shared.
V* StripBuffer(size_t vectors) {
  thread_local hwy::AlignedFreeUniquePtr<uint64_t[]> buffer;
  thread_local size_t capacity = 0;
  const size_t need = vectors * hn::Lanes(D());
  if (need > capacity) {
    buffer = hwy::AllocateAligned<uint64_t>(need);
    capacity = need;
  }
  return reinterpret_cast<V*>(buffer.get());
}

// G rows of the product added into acc[lo..p) column by column: the G carries stay in
// registers, so each full adder costs one L1 load and no store. x = (a << shift) & m ^ inv
// with a's planes zero below bit 0 (aBuf[-p..-1] = 0): a subtracted row (inv = ones, carry
// in 1) is neutral below its shift, as ~0 + carry 1 passes the sum through with carry 1.
template <int G, bool kOnes>
HWY_NOINLINE void MulRows(const V* aBuf, const V* m, const V* inv, const int* shift, int lo,
                          int p, V* acc) {
  V carry[G], mr[G], ir[G];
  const V* ar[G];
  HWY_UNROLL(8)
  for (int r = 0; r < G; ++r) {
    ir[r] = inv[r];
    mr[r] = kOnes ? inv[r] : m[r];
    carry[r] = inv[r];  // a subtracted row adds ~x + 1
    ar[r] = aBuf - std::min(shift[r], p);  // a row shifted past the top adds nothing
  }
  for (int i = lo; i < p; ++i) {
    V s = acc[i];
    HWY_UNROLL(8)
    for (int r = 0; r < G; ++r) {
      const V x = kOnes ? hn::Xor(ar[r][i], ir[r]) : AndXor(ar[r][i], mr[r], ir[r]);
      FullAdd(s, x, carry[r], s);
    }
    acc[i] = s;
  }
}

template <bool kOnes>
void MulRowsAny(int g, const V* aBuf, const V* m, const V* inv, const int* shift, int lo,
                int p, V* acc) {
  switch (g) {
    case 1: return MulRows<1, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 2: return MulRows<2, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 3: return MulRows<3, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 4: return MulRows<4, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 5: return MulRows<5, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 6: return MulRows<6, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    case 7: return MulRows<7, kOnes>(aBuf, m, inv, shift, lo, p, acc);
    default: return MulRows<8, kOnes>(aBuf, m, inv, shift, lo, p, acc);
  }
}

constexpr int kMulGroup = 8;

// Strip-mined: for each vector of PEs, a's planes are copied once into an L1 buffer (so
// planes a layer-stride apart never fight over cache sets), the product accumulates in an
// L1 column buffer, kMulGroup rows at a time, and each output plane is stored once (or
// the product is rounded and fitted from the buffer, never stored).
void Mul(const MulArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int p = g.p;
  // Layout: p zero vectors (a below bit 0), p vectors of a, p of acc, rows of m and inv.
  V* buf = StripBuffer(3 * static_cast<size_t>(p) + 2 * static_cast<size_t>(g.rows) + 1);
  V* aBuf = buf + p;
  V* acc = aBuf + p;
  V* m = acc + p;
  V* inv = m + g.rows;
  for (int i = 0; i < p; ++i) buf[i] = hn::Zero(d);
  bool ones = true;
  for (int r = 0; r < g.rows; ++r) {
    ones &= g.row[r] == g.row[0];
    inv[r] = g.sub[r] ? hn::Set(d, ~uint64_t{0}) : hn::Zero(d);
  }
  // A row list of one repeated plane that is all ones (a uni constant's rows) needs no AND.
  if (g.rows > 0 && ones) {
    for (size_t w = 0; w < words && ones; ++w) ones = g.row[0][w] == ~uint64_t{0};
  }
  for (size_t w = 0; w < words; w += lanes) {
    for (int i = 0; i < p; ++i) {
      aBuf[i] = hn::Load(d, g.a[i] + w);
      acc[i] = hn::Zero(d);
    }
    for (int r0 = 0; r0 < g.rows; r0 += kMulGroup) {
      const int n = std::min(kMulGroup, g.rows - r0);
      int lo = p;
      for (int r = r0; r < r0 + n; ++r) {
        lo = std::min(lo, std::min(g.shift[r], p));
        if (!ones) m[r] = hn::Load(d, g.row[r] + w);
      }
      if (ones) MulRowsAny<true>(n, aBuf, m + r0, inv + r0, g.shift + r0, lo, p, acc);
      else MulRowsAny<false>(n, aBuf, m + r0, inv + r0, g.shift + r0, lo, p, acc);
    }
    if (g.fit) {  // round and fit straight from the L1 column buffer
      auto bit = [&](int j) {
        if (j < 0) return hn::Zero(d);
        if (j >= p) return g.productSigned ? acc[p - 1] : hn::Zero(d);
        return acc[j];
      };
      const V carry = g.fitNearest && g.fitLo > 0 ? bit(g.fitLo - 1) : hn::Zero(d);
      RoundFitStrip(*g.fit, w, carry, [&](int i) { return bit(g.fitLo + i); });
    } else {
      for (int i = 0; i < p; ++i) hn::Store(acc[i], d, g.out[i] + w);
    }
  }
}

void Select(const Word* mask, const Word* const* a, const Word* const* b, Word* const* out,
            int n, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  for (size_t w = 0; w < words; w += lanes) {
    const V m = hn::Load(d, mask + w);
    for (int i = 0; i < n; ++i)
      hn::Store(Mux(m, hn::Load(d, a[i] + w), hn::Load(d, b[i] + w)), d, out[i] + w);
  }
}

void Equal(const Word* const* a, const Word* const* b, int n, Word* out, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  for (size_t w = 0; w < words; w += lanes) {
    V diff = hn::Zero(d);
    for (int i = 0; i < n; ++i)
      diff = hn::Or(diff, hn::Xor(hn::Load(d, a[i] + w), hn::Load(d, b[i] + w)));
    hn::Store(hn::Not(diff), d, out + w);
  }
}

void Logic(LogicOp op, const Word* a, const Word* b, Word* out, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  for (size_t w = 0; w < words; w += lanes) {
    const V x = hn::Load(d, a + w);
    const V y = b ? hn::Load(d, b + w) : hn::Zero(d);
    V r;
    switch (op) {
      case LogicOp::And: r = hn::And(x, y); break;
      case LogicOp::Or: r = hn::Or(x, y); break;
      case LogicOp::Xor: r = hn::Xor(x, y); break;
      case LogicOp::AndNot: r = hn::AndNot(y, x); break;
      default: r = hn::Not(x); break;
    }
    hn::Store(r, d, out + w);
  }
}

// Restoring division and square root: per vector of PEs every step runs on L1 vectors (x:
// the shifted remainder R', y: the divisor or trial, t: the difference), so only the
// operands' and results' planes touch memory. The new remainder is written in place from
// the top down: x[q + shift] = bit ? t[q] : x[q] reads x[q] before it is overwritten.
void Divide(const DivideArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int n = g.d + 1;
  // x: R' (n vectors; R is x[1..n)), y: the divisor, t: the difference.
  V* x = StripBuffer(3 * static_cast<size_t>(n));
  V* y = x + n;
  V* t = y + n;
  for (size_t w = 0; w < words; w += lanes) {
    for (int q = 0; q < n; ++q) y[q] = hn::Load(d, g.divisor[q] + w);
    for (int q = 0; q < g.d; ++q)
      x[q + 1] = q < g.skipped ? hn::Load(d, g.dividend[g.steps + q] + w) : hn::Zero(d);
    for (int i = g.steps - 1; i >= 0; --i) {
      x[0] = hn::Load(d, g.dividend[i] + w);
      // The new remainder R goes to x[1..n) for the next step.
      V carry = hn::Set(d, ~uint64_t{0});
      for (int q = 0; q < n; ++q) FullAdd(x[q], hn::Not(y[q]), carry, t[q]);
      const V bit = hn::Not(t[n - 1]);
      for (int q = n - 2; q >= 0; --q) x[q + 1] = Mux(bit, t[q], x[q]);
      hn::Store(bit, d, g.quotient[i] + w);
    }
    if (g.remainder)
      for (int q = 0; q < g.d; ++q) hn::Store(x[q + 1], d, g.remainder[q] + w);
  }
}

void Sqrt(const SqrtArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int nr = g.rootBits;
  const int n = nr + 2;  // the widest step
  // x: R' (x[2..) is R), y: the trial 4Y + 1, t: the difference, root: the bits so far.
  V* x = StripBuffer(4 * static_cast<size_t>(n) + 1);
  V* y = x + n + 1;
  V* t = y + n;
  V* root = t + n;
  for (size_t w = 0; w < words; w += lanes) {
    x[2] = hn::Zero(d);  // R = 0 (one position)
    y[0] = hn::Set(d, ~uint64_t{0});
    y[1] = hn::Zero(d);
    for (int j = 0; j < nr; ++j) {
      const int i = nr - 1 - j, m = j + 3;  // m positions: 2 new bits and R's j+1
      x[0] = hn::Load(d, g.radicand[2 * i] + w);
      x[1] = hn::Load(d, g.radicand[2 * i + 1] + w);
      // trial = (1, 0, root[i+1], ..., root[nr-1], 0): y[2 + k] = root[i + 1 + k].
      for (int k = 0; k < j; ++k) y[2 + k] = root[i + 1 + k];
      y[m - 1] = hn::Zero(d);
      V carry = hn::Set(d, ~uint64_t{0});
      for (int q = 0; q < m; ++q) FullAdd(x[q], hn::Not(y[q]), carry, t[q]);
      const V bit = hn::Not(t[m - 1]);
      root[i] = bit;
      // The new R has m-1 positions and becomes x[2..m+1) of the next step.
      for (int q = m - 2; q >= 0; --q) x[q + 2] = Mux(bit, t[q], x[q]);
      hn::Store(bit, d, g.root[i] + w);
    }
  }
}

const PlaneKernels* GetTable() {
  static const PlaneKernels table = {hwy::TargetName(HWY_TARGET), &Add, &RoundFit, &Mul,
                                     &Select, &Equal, &Logic, &Divide, &Sqrt};
  return &table;
}

}  // namespace zephyr::bitserial::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zephyr::bitserial {
HWY_EXPORT(GetTable);

const PlaneKernels& Kernels() { return *HWY_DYNAMIC_DISPATCH(GetTable)(); }
}  // namespace zephyr::bitserial
#endif
