// bitserial/kernels.cpp — compiled once per Highway target (foreach_target.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "bitserial/kernels.cpp"
#include "bitserial/kernels.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "hwy/aligned_allocator.h"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace zephyr::bitserial::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<uint64_t>;
using V = hn::Vec<D>;

// A full adder. On AVX-512 it is two vpternlog (Highway 1.0.3 has no general ternary-logic
// op, so the raw intrinsic); elsewhere the portable five-op form.
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

// Bitwise mux: m ? a : b, written with And/AndNot. Not IfVecThenElse: on AVX2/SSE4 its
// blendv reads only each byte's top bit, so a per-bit mask gives a wrong plane.
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
  if (g.invertB)
    ovf ? AddRange<true, true>(g, 0, words) : AddRange<true, false>(g, 0, words);
  else
    ovf ? AddRange<false, true>(g, 0, words) : AddRange<false, false>(g, 0, words);
}

// Per-thread scratch, reused, grown on demand, never shared: kSlot 0 holds one strip of a
// multiply, divide or square root (StripBuffer), kSlot 1 roundFit's sums (FitBuffer; the
// multiply's column buffer is still in use while it fits).
template <int kSlot>
V* ThreadScratch(size_t vectors) {
  thread_local hwy::AlignedFreeUniquePtr<uint64_t[]> buffer;
  thread_local size_t capacity = 0;
  const size_t need = vectors * hn::Lanes(D());
  if (need > capacity) {
    buffer = hwy::AllocateAligned<uint64_t>(need);
    capacity = need;
  }
  return reinterpret_cast<V*>(buffer.get());
}
V* StripBuffer(size_t vectors) { return ThreadScratch<0>(vectors); }
V* FitBuffer(size_t vectors) { return ThreadScratch<1>(vectors); }

// One vector of PEs of roundFit; src(i) gives exact bit lo + i (i < g.k), carry the round
// bit. The sums wait in `sums` (g.wo vectors) until the overflow is known, so each output
// plane is stored once, saturated or not. The fields are copied into locals: a store
// through out[i] could otherwise alias them.
template <class Src>
HWY_INLINE void RoundFitStrip(const RoundFitArgs& g, size_t w, V carry, const Src& src, V* sums) {
  const D d;
  const int k = g.k, wo = g.wo;
  const bool outSigned = g.outSigned;
  Word* const* const out = g.out;
  V ovf = hn::Zero(d), sum = hn::Zero(d);
  const int kept = std::min(k, wo);
  for (int i = 0; i < kept; ++i) {
    const V x = src(i);
    sum = hn::Xor(x, carry);
    carry = hn::And(x, carry);
    sums[i] = sum;
  }
  // Bits at and above wo must all equal the kept sign (or be 0 for an unsigned result).
  const V ref = outSigned && kept == wo && wo > 0 ? sums[wo - 1] : hn::Zero(d);
  for (int i = kept; i < k; ++i) {
    const V x = src(i);
    sum = hn::Xor(x, carry);
    carry = hn::And(x, carry);
    ovf = hn::Or(ovf, hn::Xor(sum, ref));
  }
  // `sum` is now the top (sign-extension) bit of the rounded exact value.
  if (g.saturate) {
    const V neg = sum;
    const V notNeg = hn::Not(neg);
    for (int i = 0; i + 1 < wo; ++i) hn::Store(Mux(ovf, notNeg, sums[i]), d, out[i] + w);
    if (wo > 0) hn::Store(Mux(ovf, outSigned ? neg : notNeg, sums[wo - 1]), d, out[wo - 1] + w);
  } else {
    for (int i = 0; i < wo; ++i) hn::Store(sums[i], d, out[i] + w);
  }
  if (g.ovf) {
    const V old = hn::Load(d, g.ovf + w);
    hn::Store(hn::OrAnd(old, ovf, hn::Load(d, g.act + w)), d, g.ovf + w);
  }
}

void RoundFit(const RoundFitArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  V* sums = FitBuffer(static_cast<size_t>(g.wo));
  for (size_t w = 0; w < words; w += lanes) {
    const V carry = g.roundBit ? hn::Load(d, g.roundBit + w) : hn::Zero(d);
    RoundFitStrip(
        g, w, carry, [&](int i) { return hn::Load(d, g.src[i] + w); }, sums);
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

// G rows of the product added into acc[lo..end) column by column: the G carries stay in
// registers, so each full adder costs one L1 load and no store. Row r's bit at column i is
// x = src[r][i] (or (src[r][i] & m[r]) ^ inv[r][i]), zero outside the row's columns (the
// buffers are zero there). No row inverts a bit below `mid`, so there x is src & m and
// inv is not read: a second L1 load per full adder is what the rows' inversions cost
// (on AVX3 the loop is bound by loads). Past `end` no row has bits: the carries ripple on
// (half adders) until all are zero, and the rest of acc is then unchanged.
template <int G, bool kOnes>
HWY_NOINLINE void MulRows(const V* const* src, const V* mr, const V* const* inv, int lo, int mid,
                          int end, int p, V* acc) {
  const D d;
  // The multipliers are copied into locals: mr points into the strip buffer acc lives in,
  // so GCC would reload them after every store to acc (on AVX3 they fit in registers).
  V carry[G], mv[G];
  HWY_UNROLL(8)
  for (int r = 0; r < G; ++r) {
    carry[r] = hn::Zero(d);
    mv[r] = kOnes ? hn::Zero(d) : mr[r];
  }
  for (int i = lo; i < (kOnes ? end : mid); ++i) {
    V s = acc[i];
    HWY_UNROLL(8)
    for (int r = 0; r < G; ++r) {
      const V x = kOnes ? src[r][i] : hn::And(src[r][i], mv[r]);
      FullAdd(s, x, carry[r], s);
    }
    acc[i] = s;
  }
  for (int i = mid; !kOnes && i < end; ++i) {
    V s = acc[i];
    HWY_UNROLL(8)
    for (int r = 0; r < G; ++r) {
      const V x = AndXor(src[r][i], mv[r], inv[r][i]);
      FullAdd(s, x, carry[r], s);
    }
    acc[i] = s;
  }
  for (int i = end; i < p; ++i) {
    V s = acc[i], any = hn::Zero(d);
    HWY_UNROLL(8)
    for (int r = 0; r < G; ++r) {
      const V c = carry[r];
      carry[r] = hn::And(s, c);
      s = hn::Xor(s, c);
      any = hn::Or(any, carry[r]);
    }
    acc[i] = s;
    if (hn::AllFalse(d, hn::Ne(any, hn::Zero(d)))) break;
  }
}

template <bool kOnes>
void MulRowsAny(int g, const V* const* src, const V* mr, const V* const* inv, int lo, int mid,
                int end, int p, V* acc) {
  switch (g) {
    case 1:
      return MulRows<1, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 2:
      return MulRows<2, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 3:
      return MulRows<3, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 4:
      return MulRows<4, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 5:
      return MulRows<5, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 6:
      return MulRows<6, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    case 7:
      return MulRows<7, kOnes>(src, mr, inv, lo, mid, end, p, acc);
    default:
      return MulRows<8, kOnes>(src, mr, inv, lo, mid, end, p, acc);
  }
}

// Rows per MulRows pass. A pass keeps its rows' carries and multipliers in registers and
// runs full adders over all its columns (zeros outside each row), so more rows per pass
// mean fewer passes over acc but more idle adders and, past the register file, spills:
// AVX3 has 32 vector registers, the other targets 16. Picked by interleaved bench_bitserial
// runs (docs/bitserial.md, "Speed"): 6 on AVX3, 4 elsewhere (8 spilled on AVX2).
#if HWY_TARGET <= HWY_AVX3
constexpr int kMulGroup = 6;
#else
constexpr int kMulGroup = 4;
#endif
static_assert(kMulGroup >= 1 && kMulGroup <= 8, "MulRowsAny instantiates 1 to 8 rows");

// Adds (or subtracts) 2^e to the little-endian limbs k, modulo 2^(64 k.size()).
void AddPowerOfTwo(std::vector<uint64_t>& k, int e, bool subtract) {
  uint64_t v = uint64_t{1} << (e % 64);
  for (size_t i = static_cast<size_t>(e / 64); i < k.size(); ++i, v = 1) {
    const uint64_t old = k[i];
    k[i] = subtract ? old - v : old + v;
    if (subtract ? old >= v : k[i] >= old) break;  // no borrow / carry out
  }
}

// The product in Baugh–Wooley form (Baugh & Wooley 1973): with A of n bits (its own planes;
// a[n..p) are only its extension), each row is n bits wide instead of running to the top,
// and every sign correction is one constant K (mod 2^p) the accumulator starts from.
// Writing A = sum_{i<n-1} a_i 2^i - a_top 2^(n-1) (unsigned: + a_top 2^(n-1)):
//   +m A 2^s = [sum_{i<n-1} (m a_i) 2^i + ~(m a_top) 2^(n-1)] 2^s - 2^(n-1+s)
//   -m A 2^s = [sum_{i<n-1} ~(m a_i) 2^i + (m a_top) 2^(n-1)] 2^s - (2^(n-1) - 1) 2^s
// and for unsigned A: +m A 2^s as is, -m A 2^s = [sum_i ~(m a_i) 2^i] 2^s - (2^n - 1) 2^s.
// A uni constant's rows (m all ones) take these as they stand: the row bits are a's planes
// with the inversions applied once per vector of PEs (pos and neg below).
// Other rows keep every inversion off all but one column of the row, so that MulRows can
// run the columns below the group's first inverted bit without reading inv[]: a -row
// adds m times C = -A (computed once per vector of PEs; n + 1 bits, signed, as -A may need
// the extra bit), so it is a +row of C with C's top inverted:
//   -m A 2^s = m C 2^s = [sum_{i<n} (m c_i) 2^i + ~(m c_n) 2^n] 2^s - 2^(n+s)
// and a +row inverts only its top bit (signed A) or nothing (unsigned A).
// Strip-mined: for each vector of PEs, a's planes are copied once into L1 buffers (so
// planes a layer-stride apart never fight over cache sets), the product accumulates in an
// L1 column buffer, kMulGroup rows at a time, and each output plane is stored once (or
// the product is rounded and fitted from the buffer, never stored).
void Mul(const MulArgs& g, size_t words) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  const int p = g.p;
  if (p <= 0) return;
  const int n = g.aBits > 0 ? std::min(g.aBits, p) : p;
  const bool aSigned = g.aBits > 0 && g.aBits <= p && g.aSigned;
  // The rows that reach below bit p.
  thread_local std::vector<int> rowIndex, st;
  rowIndex.clear(), st.clear();
  for (int r = 0; r < g.rows; ++r) {
    if (g.shift[r] >= p) continue;  // a row shifted past the top adds nothing
    rowIndex.push_back(r);
    st.push_back(g.shift[r]);
  }
  const int rows = static_cast<int>(rowIndex.size());
  bool ones = rows > 0, anySub = false;
  for (int r = 0; r < rows; ++r) {
    ones &= g.row[rowIndex[r]] == g.row[rowIndex[0]];
    anySub |= g.sub[rowIndex[r]] != 0;
  }
  // A row list of one repeated plane that is all ones (a uni constant's rows) needs no AND.
  if (ones) {
    for (size_t w = 0; w < words && ones; ++w) ones = g.row[rowIndex[0]][w] == ~uint64_t{0};
  }
  // The constant K, and the first column each row inverts (p: none below p).
  thread_local std::vector<uint64_t> k;
  k.assign((static_cast<size_t>(p) + 63) / 64, 0);
  thread_local std::vector<int> firstInv;
  firstInv.assign(rows, p);
  for (int r = 0; r < rows; ++r) {
    const int s = st[r];
    const bool sub = g.sub[rowIndex[r]] != 0;
    if (!ones && sub) {
      if (n + s < p) AddPowerOfTwo(k, n + s, true), firstInv[r] = n + s;
    } else if (aSigned) {
      if (n - 1 + s < p) AddPowerOfTwo(k, n - 1 + s, true), firstInv[r] = n - 1 + s;
      if (sub) AddPowerOfTwo(k, s, false);
    } else if (sub) {
      if (n + s < p) AddPowerOfTwo(k, n + s, true);
      AddPowerOfTwo(k, s, false);
    }
  }
  // The fit reads product bits fitLo - 1 .. fitLo + k - 1: acc has `below` zero vectors
  // under bit 0 and `above` vectors over bit p - 1 (the product's sign or zero), so it reads
  // them straight from acc.
  const int fitLo = g.fitLo;
  const int below = g.fit ? std::max(0, 1 - fitLo) : 0;
  const int above = g.fit ? std::max(0, fitLo + g.fit->k - p) : 0;
  // Layout (vectors): pos and neg (ones rows: a's bits for +row, the top one inverted if
  // signed, and their complements for -row; other rows: a's bits in pos and C = -A's in
  // neg, the inversions of their tops in invPos and invNeg), 2p each with column 0 at p
  // and zero outside [0, n) (C: [0, n]); acc (below + p + above) and its start K (p); the
  // rows' multiplier vectors.
  V* buf = StripBuffer(10 * static_cast<size_t>(p) + static_cast<size_t>(below + above + rows) + 1);
  V* pos = buf + p;
  V* neg = pos + 2 * p;
  V* invPos = neg + 2 * p;
  V* invNeg = invPos + 2 * p;
  V* acc = invNeg + p + below;
  V* start = acc + p + above;
  V* m = start + p;
  for (int i = -p; i < p; ++i) {
    pos[i] = neg[i] = invPos[i] = invNeg[i] = hn::Zero(d);
  }
  for (int i = -below; i < 0; ++i) acc[i] = hn::Zero(d);
  for (int i = 0; i < p; ++i)
    start[i] = (k[i / 64] >> (i % 64)) & 1 ? hn::Set(d, ~uint64_t{0}) : hn::Zero(d);
  const V allOnes = hn::Set(d, ~uint64_t{0});
  if (aSigned) invPos[n - 1] = allOnes;
  if (!ones && n < p) invNeg[n] = allOnes;
  thread_local std::vector<const V*> src, inv;
  src.assign(rows, nullptr), inv.assign(rows, nullptr);
  for (int r = 0; r < rows; ++r) {
    const bool sub = g.sub[rowIndex[r]] != 0;
    src[r] = (sub ? neg : pos) - st[r];
    inv[r] = (sub ? invNeg : invPos) - st[r];
  }
  // Each group's columns: from its lowest shift, uninverted below mid, rows to end.
  thread_local std::vector<int> groupLo, groupMid, groupEnd;
  groupLo.clear(), groupMid.clear(), groupEnd.clear();
  for (int r0 = 0; r0 < rows; r0 += kMulGroup) {
    int lo = p, mid = p, end = 0;
    for (int r = r0; r < std::min(rows, r0 + kMulGroup); ++r) {
      const bool wide = !ones && g.sub[rowIndex[r]] != 0;  // C has n + 1 bits
      lo = std::min(lo, st[r]);
      mid = std::min(mid, firstInv[r]);
      end = std::max(end, std::min(st[r] + n + (wide ? 1 : 0), p));
    }
    groupLo.push_back(lo);
    groupMid.push_back(std::clamp(mid, lo, end));
    groupEnd.push_back(end);
  }
  const int cBits = std::min(n + 1, p);  // C's bits below p
  V* sums = g.fit ? FitBuffer(static_cast<size_t>(g.fit->wo)) : nullptr;
  const bool productSigned = g.productSigned;
  for (size_t w = 0; w < words; w += lanes) {
    if (ones) {
      for (int i = 0; i < n; ++i) {
        pos[i] = hn::Xor(hn::Load(d, g.a[i] + w), invPos[i]);
        if (anySub) neg[i] = hn::Not(pos[i]);
      }
    } else {
      for (int i = 0; i < n; ++i) pos[i] = hn::Load(d, g.a[i] + w);
      if (anySub) {  // C = ~A + 1 over n + 1 bits (A sign- or zero-extended)
        V carry = allOnes;
        for (int i = 0; i < cBits; ++i) {
          const V na = hn::Not(i < n ? pos[i] : aSigned ? pos[n - 1] : hn::Zero(d));
          neg[i] = hn::Xor(na, carry);
          carry = hn::And(na, carry);
        }
      }
    }
    std::memcpy(static_cast<void*>(acc), start, static_cast<size_t>(p) * sizeof(V));
    for (int r0 = 0, gi = 0; r0 < rows; r0 += kMulGroup, ++gi) {
      const int cnt = std::min(kMulGroup, rows - r0);
      if (ones) {
        MulRowsAny<true>(cnt, src.data() + r0, m + r0, inv.data() + r0, groupLo[gi], groupEnd[gi],
                         groupEnd[gi], p, acc);
      } else {
        for (int r = r0; r < r0 + cnt; ++r) m[r] = hn::Load(d, g.row[rowIndex[r]] + w);
        MulRowsAny<false>(cnt, src.data() + r0, m + r0, inv.data() + r0, groupLo[gi], groupMid[gi],
                          groupEnd[gi], p, acc);
      }
    }
    if (g.fit) {  // round and fit straight from the L1 column buffer
      const V top = productSigned ? acc[p - 1] : hn::Zero(d);
      for (int i = 0; i < above; ++i) acc[p + i] = top;
      const V carry = g.fitNearest && fitLo > 0 ? acc[fitLo - 1] : hn::Zero(d);
      RoundFitStrip(
          *g.fit, w, carry, [&](int i) { return acc[fitLo + i]; }, sums);
    } else {
      for (int i = 0; i < p; ++i) hn::Store(acc[i], d, g.out[i] + w);
    }
  }
}

void Select(const Word* mask, const Word* const* a, const Word* const* b, Word* const* out, int n,
            size_t words) {
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
      case LogicOp::kAnd:
        r = hn::And(x, y);
        break;
      case LogicOp::kOr:
        r = hn::Or(x, y);
        break;
      case LogicOp::kXor:
        r = hn::Xor(x, y);
        break;
      case LogicOp::kAndNot:
        r = hn::AndNot(y, x);
        break;
      default:
        r = hn::Not(x);
        break;
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
  static const PlaneKernels table = {
      hwy::TargetName(HWY_TARGET), &Add, &RoundFit, &Mul, &Select, &Equal, &Logic, &Divide, &Sqrt};
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
