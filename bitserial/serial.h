// bitserial/serial.h — the second way a schedule is counted (bitserial/cost.h is the first):
// a bit-serial unit that runs passes over planes with the machine's kernels and counts each
// pass's micro-ops as it goes, so the schedule charged is the one executed. MultiC's float
// operations (bitserial/float.cpp) are written on it; their counts depend on the format
// alone, never on the data (docs/float.md gives the closed forms). Internal to bitserial/.
#pragma once

#include <initializer_list>
#include <unordered_map>
#include <vector>

#include "bitserial/cost.h"
#include "bitserial/internals.h"
#include "bitserial/machine.h"
#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::bitserial::serial {

// Where a plane lives, which decides what reading or writing one of its bits costs:
// PE memory, the accumulator (the MPP's shift register; internal memory on the
// WaveTracer), a PE flag register (loading it is a flagOp, the ALU reads it for free) or
// a constant the controller supplies (free).
enum class Loc : unsigned char { kInternal, kExternal, kAcc, kFlag, kConst };

using Planes = std::vector<const Word*>;
using OutPlanes = std::vector<Word*>;

inline Planes Slice(const Planes& v, int from, int to) {
  return Planes(v.begin() + from, v.begin() + to);
}
inline Planes Concat(std::initializer_list<Planes> parts) {
  Planes r;
  for (const Planes& p : parts) r.insert(r.end(), p.begin(), p.end());
  return r;
}
inline Planes In(const OutPlanes& v) { return Planes(v.begin(), v.end()); }

inline int CeilLog2(int n) {
  int k = 0;
  while ((1 << k) < n) ++k;
  return k;
}

// The bit-serial unit: runs passes over planes with the machine's kernels and counts
// each pass's micro-ops as it goes, so the schedule charged is the one executed. Nothing
// here branches on data: the counts depend on the format alone.
class Serial {
 public:
  explicit Serial(Machine& m) : m_(m), words_(m.WordsPerPlane()) {
    loc_[m.ZeroPlane()] = Loc::kConst;
    loc_[m.OnesPlane()] = Loc::kConst;
  }
  ~Serial() {
    for (Word* p : owned_) m_.ReleasePlanes(p, 1);
  }
  Serial(const Serial&) = delete;
  Serial& operator=(const Serial&) = delete;

  Machine& M() { return m_; }
  const MicroOpCounts& Counts() const { return c_; }
  const Word* Zero() const { return m_.ZeroPlane(); }
  const Word* Ones() const { return m_.OnesPlane(); }
  // The n low bits of `value` (two's complement) as constant planes.
  Planes Const(int64_t value, int n) const {
    Planes r(n);
    for (int i = 0; i < n; ++i) r[i] = ((value >> std::min(i, 62)) & 1) ? Ones() : Zero();
    return r;
  }
  Planes Zeros(int n) const { return Planes(n, Zero()); }

  void Place(const Multi& x) {
    const Loc loc = x.IsUni()                          ? Loc::kConst
                    : x.GetSpace() == Space::kInternal ? Loc::kInternal
                                                       : Loc::kExternal;
    for (int i = 0; i < x.Width(); ++i) loc_[x.Plane(i)] = loc;
  }
  Word* New(Loc loc) {
    Word* p = m_.AcquirePlanes(1);
    std::memset(p, 0, sizeof(Word) * words_);
    owned_.push_back(p);
    loc_[p] = loc;
    return p;
  }
  OutPlanes New(int n, Loc loc) {
    OutPlanes r(n);
    for (auto& p : r) p = New(loc);
    return r;
  }

  void Read(const Word* p) {
    switch (LocOf(p)) {
      case Loc::kInternal:
        c_.Add(MicroOp::kReadInternal);
        break;
      case Loc::kExternal:
        c_.Add(MicroOp::kReadExternal);
        break;
      case Loc::kAcc:
        c_.Add(MicroOp::kAccumulatorRead);
        break;
      default:
        break;
    }
  }
  void Write(const Word* p) {
    switch (LocOf(p)) {
      case Loc::kInternal:
        c_.Add(MicroOp::kWriteInternal);
        break;
      case Loc::kExternal:
        c_.Add(MicroOp::kWriteExternal);
        break;
      case Loc::kAcc:
        c_.Add(MicroOp::kAccumulatorWrite);
        break;
      case Loc::kFlag:
        c_.Add(MicroOp::kFlagOp);
        break;
      case Loc::kConst:
        ZEPHYR_CHECK(false);
    }
  }

  // out[i] = bit i of a + (invertB ? ~b : b) + carryIn over out.size() positions; a null
  // out[i] is not stored (the adder runs past it for a carry or a sign).
  void Add(const Planes& a, const Planes& b, const OutPlanes& out, bool invertB, bool carryIn) {
    const int n = static_cast<int>(out.size());
    ZEPHYR_CHECK(static_cast<int>(a.size()) == n && static_cast<int>(b.size()) == n);
    c_.Add(MicroOp::kFlagOp);  // clear or set the carry
    for (int i = 0; i < n; ++i) {
      Read(a[i]), Read(b[i]);
      c_.Add(MicroOp::kAluStep);
      if (out[i]) Write(out[i]);
    }
    AddArgs args{a.data(), b.data(), out.data(), n, invertB, carryIn, 0, false, nullptr, nullptr};
    m_.Kernels().add(args, words_);
  }

  // out[i] = mask ? a[i] : b[i], the mask loaded into the PE's mask register. Where
  // out[i] is b[i] the write is simply gated by the mask and b[i] is not read. The
  // kernel runs i upwards: an in-place move may read only positions not yet written.
  void Mux(const Word* mask, const Planes& a, const Planes& b, const OutPlanes& out) {
    const int n = static_cast<int>(out.size());
    ZEPHYR_CHECK(static_cast<int>(a.size()) == n && static_cast<int>(b.size()) == n);
    Read(mask);
    c_.Add(MicroOp::kFlagOp);
    for (int i = 0; i < n; ++i) {
      Read(a[i]);
      if (out[i] != b[i] && a[i] != b[i]) Read(b[i]);
      c_.Add(MicroOp::kAluStep);
      Write(out[i]);
    }
    m_.Kernels().select(mask, a.data(), b.data(), out.data(), n, words_);
  }

  // A boolean of one or two planes into a new plane at `loc` (or into `into`).
  const Word* Logic(LogicOp op, const Word* x, const Word* y, Loc loc, Word* into = nullptr) {
    Read(x);
    if (y) Read(y);
    c_.Add(MicroOp::kAluStep);
    Word* o = into ? into : New(loc);
    Write(o);
    m_.Kernels().logic(op, x, y, o, words_);
    return o;
  }
  const Word* And(const Word* x, const Word* y, Loc loc = Loc::kFlag) {
    return Logic(LogicOp::kAnd, x, y, loc);
  }
  const Word* Or(const Word* x, const Word* y, Loc loc = Loc::kFlag) {
    return Logic(LogicOp::kOr, x, y, loc);
  }
  const Word* Xor(const Word* x, const Word* y, Loc loc = Loc::kFlag) {
    return Logic(LogicOp::kXor, x, y, loc);
  }
  const Word* AndNot(const Word* x, const Word* y, Loc loc = Loc::kFlag) {
    return Logic(LogicOp::kAndNot, x, y, loc);
  }
  const Word* Not(const Word* x, Loc loc = Loc::kFlag) {
    return Logic(LogicOp::kNot, x, nullptr, loc);
  }

  // 1 where every plane is 0 (none) or 1 (all): one serial OR/AND over the planes.
  const Word* NoneOf(const Planes& x, Loc loc = Loc::kFlag) { return Scan(x, Zero(), loc); }
  const Word* AllOf(const Planes& x, Loc loc = Loc::kFlag) { return Scan(x, Ones(), loc); }
  const Word* AnyOf(const Planes& x, Loc loc = Loc::kFlag) {
    if (x.empty()) return Zero();
    const Word* none = Scan(x, Zero(), Loc::kFlag);
    Word* o = New(loc);
    m_.Kernels().logic(LogicOp::kNot, none, nullptr, o, words_);  // the same latch, inverted
    if (loc != Loc::kFlag) Write(o);
    return o;
  }

  // out[i] = a[i]: one pass.
  void Copy(const Planes& a, const OutPlanes& out) {
    ZEPHYR_CHECK(a.size() == out.size());
    for (size_t i = 0; i < a.size(); ++i) Read(a[i]), c_.Add(MicroOp::kAluStep), Write(out[i]);
    m_.Kernels().select(Ones(), a.data(), a.data(), out.data(), static_cast<int>(a.size()), words_);
  }
  // "a == b in every position", latched by a pass that reads both anyway: only the latch
  // is charged.
  const Word* EqualAlong(const Planes& a, const Planes& b) {
    Word* o = New(Loc::kFlag);
    m_.Kernels().equal(a.data(), b.data(), static_cast<int>(a.size()), o, words_);
    c_.Add(MicroOp::kFlagOp);
    return o;
  }
  // Adds the counts of a pass run by another layer (a fixed-point conversion).
  void Charge(const MicroOpCounts& c) { c_ += c; }

  // Charges reads of planes that a pass takes in besides its counted operands (e.g. the
  // two sources of an operand selected on the fly).
  void ChargeReads(const Planes& x) {
    for (const Word* p : x) Read(p);
  }
  // mask ? a : b (or, with b empty, a & ~mask: a gated off where mask) computed as the
  // operand routing inside the pass that consumes it: nothing is charged here. A gated
  // plane costs what reading a[i] costs; a selected one is free to read and the consumer
  // charges the reads of both sources (ChargeReads).
  Planes Routed(const Word* mask, const Planes& a, const Planes& b) {
    Planes r(a.size());
    for (size_t i = 0; i < a.size(); ++i) {
      Word* o = New(b.empty() ? LocOf(a[i]) : Loc::kFlag);
      if (b.empty())
        m_.Kernels().logic(LogicOp::kAndNot, a[i], mask, o, words_);
      else
        m_.Kernels().select(mask, &a[i], &b[i], &o, 1, words_);
      r[i] = o;
    }
    return r;
  }
  // v ^ mask, routed into the pass that consumes it (nothing charged here).
  Planes XorRouted(const Planes& v, const Word* mask) {
    Planes r(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
      Word* o = New(Loc::kFlag);
      m_.Kernels().logic(LogicOp::kXor, v[i], mask, o, words_);
      r[i] = o;
    }
    return r;
  }
  // A serial comparison riding on the pass that produces `a` bit by bit (against a
  // constant b): only the latch of its sign is charged. out as in Add.
  void CompareAlong(const Planes& a, const Planes& b, const OutPlanes& out) {
    c_.Add(MicroOp::kFlagOp);
    AddArgs args{a.data(), b.data(), out.data(), static_cast<int>(out.size()), true, true, 0,
                 false,    nullptr,  nullptr};
    m_.Kernels().add(args, words_);
  }
  // The OR of planes that the current pass reads anyway: only the latch is charged.
  const Word* AnyOfRead(const Planes& x) {
    Word* o = New(Loc::kFlag);
    Planes ref(x.size(), Zero());
    m_.Kernels().equal(x.data(), ref.data(), static_cast<int>(x.size()), o, words_);
    m_.Kernels().logic(LogicOp::kNot, o, nullptr, o, words_);
    c_.Add(MicroOp::kFlagOp);
    return o;
  }
  // One serial pass over x that latches both "any bit set" (into a plane at `anyLoc`)
  // and "all bits set" (a flag).
  std::pair<const Word*, const Word*> AnyAll(const Planes& x, Loc anyLoc) {
    for (const Word* p : x) Read(p), c_.Add(MicroOp::kAluStep);
    Word* any = New(anyLoc);
    Write(any);
    Planes zero(x.size(), Zero()), ones(x.size(), Ones());
    m_.Kernels().equal(x.data(), zero.data(), static_cast<int>(x.size()), any, words_);
    m_.Kernels().logic(LogicOp::kNot, any, nullptr, any, words_);
    Word* all = New(Loc::kFlag);
    Write(all);
    m_.Kernels().equal(x.data(), ones.data(), static_cast<int>(x.size()), all, words_);
    return {any, all};
  }
  // out = mask ? -v : v in one serial pass (complement after the lowest one).
  void NegateWhere(const Planes& v, const Word* mask, const OutPlanes& out) {
    const int n = static_cast<int>(v.size());
    Read(mask);
    c_.Add(MicroOp::kFlagOp, 2);  // the mask, and the carry
    for (int i = 0; i < n; ++i) Read(v[i]), c_.Add(MicroOp::kAluStep), Write(out[i]);
    Planes x(n);
    for (int i = 0; i < n; ++i) {
      Word* t = New(Loc::kFlag);
      m_.Kernels().logic(LogicOp::kXor, v[i], mask, t, words_);
      x[i] = t;
    }
    Planes xi = Concat({{mask}, x}), zi = Concat({{mask}, Planes(n, Zero())});
    OutPlanes o = {nullptr};
    o.insert(o.end(), out.begin(), out.end());
    AddArgs args{xi.data(), zi.data(), o.data(), n + 1, false, false, 0, false, nullptr, nullptr};
    m_.Kernels().add(args, words_);
  }
  // Where mask: the larger-exponent significand to `big` (memory) and the other to
  // `small` (the accumulator), both operands' bits read once.
  void Swap(const Word* mask, const Planes& a, const Planes& b, const OutPlanes& big,
            const OutPlanes& small) {
    Read(mask);
    c_.Add(MicroOp::kFlagOp);
    for (size_t i = 0; i < a.size(); ++i) {
      Read(a[i]), Read(b[i]);
      c_.Add(MicroOp::kAluStep, 2);
      Write(big[i]), Write(small[i]);
    }
    m_.Kernels().select(mask, b.data(), a.data(), big.data(), static_cast<int>(a.size()), words_);
    m_.Kernels().select(mask, a.data(), b.data(), small.data(), static_cast<int>(a.size()), words_);
  }

  // v ^= mask in place (a conditional complement): mask into a register, one pass.
  void XorWith(const OutPlanes& v, const Word* mask) {
    Read(mask);
    c_.Add(MicroOp::kFlagOp);
    for (Word* p : v) {
      Read(p);
      c_.Add(MicroOp::kAluStep);
      Write(p);
      m_.Kernels().logic(LogicOp::kXor, p, mask, p, words_);
    }
  }

  // Where mask: v >>= s, the bits that fall off (below position 1) ORed into v[0], the
  // sticky bit. One stage of a data-dependent shift.
  void ShiftRightSticky(const OutPlanes& v, const Word* mask, int s) {
    const int n = static_cast<int>(v.size());
    Planes lost(v.begin() + 1, v.begin() + std::min(s + 1, n));
    const Word* any = AnyOf(lost);
    const Word* gone = And(mask, any);
    Logic(LogicOp::kOr, v[0], gone, Loc::kAcc, v[0]);
    Planes src(n - 1), self(n - 1);
    OutPlanes dst(n - 1);
    for (int i = 1; i < n; ++i) {
      src[i - 1] = i + s < n ? v[i + s] : Zero();
      self[i - 1] = dst[i - 1] = v[i];
    }
    Mux(mask, src, self, dst);
  }

  // Where mask: v <<= s (zeros enter at the bottom); run from the top down.
  void ShiftLeft(const OutPlanes& v, const Word* mask, int s) {
    const int n = static_cast<int>(v.size());
    Planes src(n), self(n);
    OutPlanes dst(n);
    for (int j = 0; j < n; ++j) {
      const int i = n - 1 - j;
      src[j] = i - s >= 0 ? v[i - s] : Zero();
      self[j] = dst[j] = v[i];
    }
    Mux(mask, src, self, dst);
  }

  // Moves the leading one of v to the top position, `stages` binary stages from the
  // largest: stage k shifts by 2^k where the top 2^k bits are all zero. Returns u with
  // u_k = 1 where stage k did NOT shift, so the shift is (2^stages - 1) - u.
  Planes Normalise(const OutPlanes& v, int stages) {
    const int n = static_cast<int>(v.size());
    Planes u(stages, Zero());
    for (int k = stages - 1; k >= 0; --k) {
      const int s = 1 << k;
      ZEPHYR_CHECK(s < n);
      const Word* z = NoneOf(Planes(v.end() - s, v.end()));
      ShiftLeft(v, z, s);
      u[k] = Not(z, Loc::kInternal);
    }
    return u;
  }

  // The shift-and-add product of a and b (unsigned) into out (a.size() + b.size()
  // accumulator planes): per multiplier bit, its value into the mask register, a's bits
  // added into the partial product (Batcher 1980's multiply).
  void Multiply(const Planes& a, const Planes& b, const OutPlanes& out) {
    const int w = static_cast<int>(out.size());
    ZEPHYR_CHECK(w == static_cast<int>(a.size() + b.size()));
    for (size_t j = 0; j < b.size(); ++j) {
      Read(b[j]);
      c_.Add(MicroOp::kFlagOp);
      for (const Word* x : a) {
        Read(x);
        c_.Add(MicroOp::kAluStep);
        c_.Add(MicroOp::kAccumulatorRead);
        c_.Add(MicroOp::kAccumulatorWrite);
      }
    }
    Planes aw(a);
    aw.resize(w, Zero());
    std::vector<int> shift(b.size());
    std::vector<unsigned char> sub(b.size(), 0);
    for (size_t j = 0; j < b.size(); ++j) shift[j] = static_cast<int>(j);
    MulArgs args{aw.data(), w, b.data(), shift.data(), sub.data(), static_cast<int>(b.size()),
                 out.data()};
    args.aBits = static_cast<int>(a.size());  // unsigned, zero-extended above
    m_.Kernels().mul(args, words_);
  }

 private:
  Loc LocOf(const Word* p) const {
    auto it = loc_.find(p);
    ZEPHYR_CHECK(it != loc_.end());
    return it->second;
  }
  const Word* Scan(const Planes& x, const Word* value, Loc loc) {
    for (const Word* p : x) Read(p), c_.Add(MicroOp::kAluStep);
    Word* o = New(loc);
    Write(o);
    Planes ref(x.size(), value);
    m_.Kernels().equal(x.data(), ref.data(), static_cast<int>(x.size()), o, words_);
    return o;
  }

  Machine& m_;
  size_t words_;
  MicroOpCounts c_;
  std::unordered_map<const Word*, Loc> loc_;
  std::vector<Word*> owned_;
};

}  // namespace zephyr::bitserial::serial
