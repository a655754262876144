// bitserial/kernels.cpp — compiled once per Highway target (foreach_target.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "bitserial/kernels.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

#include "bitserial/kernels.h"

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

void Add(const AddArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const V ones = hn::Set(d, ~uint64_t{0});
  for (size_t w = 0; w < words; w += lanes) {
    V carry = g.carryIn ? ones : hn::Zero(d);
    V ref = hn::Zero(d), ovf = hn::Zero(d);
    for (int p = 0; p < g.n; ++p) {
      const V x = hn::Load(d, g.a[p] + w);
      V y = hn::Load(d, g.b[p] + w);
      if (g.invertB) y = hn::Not(y);
      V sum;
      FullAdd(x, y, carry, sum);
      if (g.out[p]) hn::Store(sum, d, g.out[p] + w);
      if (g.ovf && p >= g.ovfFrom) {
        if (p == g.ovfFrom && g.ovfSigned) ref = sum;
        ovf = hn::Or(ovf, hn::Xor(sum, ref));
      }
    }
    if (g.ovf) {
      const V old = hn::Load(d, g.ovf + w);
      hn::Store(hn::OrAnd(old, ovf, hn::Load(d, g.act + w)), d, g.ovf + w);
    }
  }
}

void RoundFit(const RoundFitArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const V ones = hn::Set(d, ~uint64_t{0});
  for (size_t w = 0; w < words; w += lanes) {
    V carry = g.roundBit ? hn::Load(d, g.roundBit + w) : hn::Zero(d);
    V ref = hn::Zero(d), ovf = hn::Zero(d), sum = hn::Zero(d);
    for (int i = 0; i < g.k; ++i) {
      const V x = hn::Load(d, g.src[i] + w);
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
    (void)ones;
  }
}

void Mul(const MulArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const V ones = hn::Set(d, ~uint64_t{0});
  for (size_t w = 0; w < words; w += lanes) {
    for (int i = 0; i < g.p; ++i) hn::Store(hn::Zero(d), d, g.out[i] + w);
    for (int r = 0; r < g.rows; ++r) {
      const V m = hn::Load(d, g.row[r] + w);
      const bool sub = g.sub[r] != 0;
      V carry = sub ? ones : hn::Zero(d);
      const int s = g.shift[r];
      for (int i = s; i < g.p; ++i) {
        V x = hn::And(hn::Load(d, g.a[i - s] + w), m);
        if (sub) x = hn::Not(x);
        const V acc = hn::Load(d, g.out[i] + w);
        V sum;
        FullAdd(acc, x, carry, sum);
        hn::Store(sum, d, g.out[i] + w);
      }
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

const PlaneKernels* GetTable() {
  static const PlaneKernels table = {hwy::TargetName(HWY_TARGET), &Add, &RoundFit, &Mul,
                                     &Select, &Equal, &Logic};
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
