#include "bitserial/multi.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "bitserial/internals.h"
#include "fixed/check.h"

namespace zephyr::bitserial {

using fixed::Format;
using fixed::Policy;

namespace {

// The plane of operand `x` at exact position p when x's bit 0 sits at `offset`: zero below
// x, x's sign plane (or zero) above it.
const Word* PlaneAt(const Multi& x, int offset, int p) {
  const int q = p - offset;
  const int w = x.Width();
  if (q < 0) return x.GetMachine().ZeroPlane();
  if (q >= w) return x.Format().isSigned ? x.Plane(w - 1) : x.GetMachine().ZeroPlane();
  return x.Plane(q);
}

// The same over raw planes (a scratch exact value of `w` planes).
const Word* RawAt(Machine& m, const Word* base, int w, bool isSigned, int q) {
  if (q < 0) return m.ZeroPlane();
  if (q >= w) return isSigned ? base + (w - 1) * m.PlaneStride() : m.ZeroPlane();
  return base + q * m.PlaneStride();
}

// Scratch planes from the machine's pool, returned on scope exit.
struct Scratch {
  Scratch(Machine& m, int planes) : m(m), n(planes), p(m.AcquirePlanes(planes)) {}
  ~Scratch() { m.ReleasePlanes(p, n); }
  Word* Plane(int i) const { return p + i * m.PlaneStride(); }
  Machine& m;
  int n;
  Word* p;
};

// Steps 2 and 3 of fixed/'s rule: the exact value (w planes at `base`, `frac` fraction
// bits, signed or not) rounded and fitted into `out`.
void RoundFitInto(Machine& m, const Word* base, int w, bool isSigned, int frac, Multi& out,
                  Policy policy, const Word* act) {
  const int wo = out.Width();
  const int lo = frac - out.Format().fracBits;
  const int k = std::max(wo + 1, w - lo + 2);
  auto& src = MachineInternals::PointersA(m);
  src.clear();
  for (int i = 0; i < k; ++i) src.push_back(RawAt(m, base, w, isSigned, lo + i));
  auto& dst = MachineInternals::PointersOut(m);
  dst.clear();
  for (int i = 0; i < wo; ++i) dst.push_back(out.Plane(i));
  RoundFitArgs args{src.data(),
                    k,
                    policy.rounding == fixed::Rounding::kNearest && lo > 0
                        ? RawAt(m, base, w, isSigned, lo - 1)
                        : nullptr,
                    dst.data(),
                    wo,
                    out.Format().isSigned,
                    policy.overflow == fixed::OverflowPolicy::kSaturate,
                    MachineInternals::Overflow(m),
                    act};
  m.Kernels().roundFit(args, m.WordsPerPlane());
}

// The same, with overflow flagged in the active PEs.
void RoundFitInto(Machine& m, const Word* base, int w, bool isSigned, int frac, Multi& out,
                  Policy policy) {
  RoundFitInto(m, base, w, isSigned, frac, out, policy, m.Activity());
}

// a + b or a - b (subtract), exactly, then rounded and fitted.
void AddInto(const Multi& a, const Multi& b, bool subtract, Multi& out, Policy policy) {
  Machine& m = a.GetMachine();
  const Format e =
      subtract ? DiffFormat(a.Format(), b.Format()) : SumFormat(a.Format(), b.Format());
  const int w = e.Width();
  const int wo = out.Width();
  const int lo = e.fracBits - out.Format().fracBits;
  const int offA = e.fracBits - a.Format().fracBits, offB = e.fracBits - b.Format().fracBits;
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  if (lo == 0 && policy.overflow == fixed::OverflowPolicy::kWrap) {
    // Fast path: the output bits are the exact sum's low bits; the adder runs on past
    // them only to latch the overflow.
    const int n = std::max(w, wo + 1);
    pa.clear(), pb.clear(), po.clear();
    for (int p = 0; p < n; ++p) {
      pa.push_back(PlaneAt(a, offA, p));
      pb.push_back(PlaneAt(b, offB, p));
      po.push_back(p < wo ? out.Plane(p) : nullptr);
    }
    const bool outSigned = out.Format().isSigned;
    AddArgs args{pa.data(),
                 pb.data(),
                 po.data(),
                 n,
                 subtract,
                 subtract,
                 outSigned ? wo - 1 : wo,
                 outSigned,
                 MachineInternals::Overflow(m),
                 m.Activity()};
    m.Kernels().add(args, m.WordsPerPlane());
    return;
  }
  Scratch exact(m, w);
  pa.clear(), pb.clear(), po.clear();
  for (int p = 0; p < w; ++p) {
    pa.push_back(PlaneAt(a, offA, p));
    pb.push_back(PlaneAt(b, offB, p));
    po.push_back(exact.Plane(p));
  }
  AddArgs args{pa.data(), pb.data(), po.data(), w, subtract, subtract, 0, false, nullptr, nullptr};
  m.Kernels().add(args, m.WordsPerPlane());
  RoundFitInto(m, exact.p, w, e.isSigned, e.fracBits, out, policy);
}

// The exact -a into `w` scratch planes (w = NegFormat(a).Width()).
void NegExact(const Multi& a, Word* base, int w) {
  Machine& m = a.GetMachine();
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int p = 0; p < w; ++p) {
    pa.push_back(m.ZeroPlane());
    pb.push_back(PlaneAt(a, 0, p));
    po.push_back(base + p * m.PlaneStride());
  }
  AddArgs args{pa.data(), pb.data(), po.data(), w, true, true, 0, false, nullptr, nullptr};
  m.Kernels().add(args, m.WordsPerPlane());
}

// mask ? a : b in the union format, into scratch planes.
void SelectExact(const Word* mask, const Multi& a, const Multi& b, const Format& u, Word* base) {
  Machine& m = a.GetMachine();
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int p = 0; p < u.Width(); ++p) {
    pa.push_back(PlaneAt(a, u.fracBits - a.Format().fracBits, p));
    pb.push_back(PlaneAt(b, u.fracBits - b.Format().fracBits, p));
    po.push_back(base + p * m.PlaneStride());
  }
  m.Kernels().select(mask, pa.data(), pb.data(), po.data(), u.Width(), m.WordsPerPlane());
}

// The plane of a < b (the sign of the exact difference) into `out`.
void LessPlane(const Multi& a, const Multi& b, Word* out) {
  Machine& m = a.GetMachine();
  const Format e = DiffFormat(a.Format(), b.Format());
  const int w = e.Width();
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int p = 0; p < w; ++p) {
    pa.push_back(PlaneAt(a, e.fracBits - a.Format().fracBits, p));
    pb.push_back(PlaneAt(b, e.fracBits - b.Format().fracBits, p));
    po.push_back(p == w - 1 ? out : nullptr);
  }
  AddArgs args{pa.data(), pb.data(), po.data(), w, true, true, 0, false, nullptr, nullptr};
  m.Kernels().add(args, m.WordsPerPlane());
}

void CheckSameMachine(const Multi& a, const Multi& b) {
  ZEPHYR_CHECK(!a.Empty() && !b.Empty());
  ZEPHYR_CHECK(&a.GetMachine() == &b.GetMachine());
}

// Product rows (shift-and-add) then round/fit, in one kernel (the exact product stays in
// the kernel's L1 buffer); rows given by the caller.
void MulInto(const Multi& a, const std::vector<const Word*>& rows, const std::vector<int>& shifts,
             const std::vector<unsigned char>& subs, const Format& product, Multi& out,
             Policy policy) {
  Machine& m = a.GetMachine();
  const int w = product.Width();
  const int wo = out.Width();
  const int lo = product.fracBits - out.Format().fracBits;
  auto& pa = MachineInternals::PointersA(m);
  pa.clear();
  for (int p = 0; p < w; ++p) pa.push_back(PlaneAt(a, 0, p));
  auto& po = MachineInternals::PointersOut(m);
  po.clear();
  for (int i = 0; i < wo; ++i) po.push_back(out.Plane(i));
  const RoundFitArgs fit{nullptr,
                         std::max(wo + 1, w - lo + 2),
                         nullptr,
                         po.data(),
                         wo,
                         out.Format().isSigned,
                         policy.overflow == fixed::OverflowPolicy::kSaturate,
                         MachineInternals::Overflow(m),
                         m.Activity()};
  MulArgs args{pa.data(),
               w,
               rows.data(),
               shifts.data(),
               subs.data(),
               static_cast<int>(rows.size()),
               nullptr,
               &fit,
               lo,
               product.isSigned,
               policy.rounding == fixed::Rounding::kNearest,
               a.Width(),
               a.Format().isSigned};
  m.Kernels().mul(args, m.WordsPerPlane());
}

// The signed digits of a uni constant's integer (its bits as a two's-complement or unsigned
// integer): (position, negative) for each nonzero digit of the non-adjacent form
// (Reitwiesner 1960), which has the fewest nonzero digits of any signed-digit form, so
// never more than the constant's one bits. Constants wider than 62 bits keep their bits
// (the sign bit subtracted).
std::vector<std::pair<int, bool>> NafDigits(const fixed::Fixed& c) {
  std::vector<std::pair<int, bool>> digits;
  const int wc = c.format.Width();
  if (wc > 62) {
    for (int j = 0; j < wc; ++j)
      if (c.Bit(j)) digits.emplace_back(j, c.format.isSigned && j == wc - 1);
    return digits;
  }
  int64_t v = 0;
  for (int j = 0; j < wc; ++j)
    if (c.Bit(j)) v += (c.format.isSigned && j == wc - 1) ? -(int64_t{1} << j) : int64_t{1} << j;
  for (int j = 0; v != 0; ++j, v >>= 1) {  // v >>= 1 is exact: v is even there
    if (v & 1) {
      const int64_t digit = 2 - (v & 3);  // +1 or -1: leaves v - digit divisible by 4
      digits.emplace_back(j, digit < 0);
      v -= digit;
    }
  }
  return digits;
}

// One row per multiplier bit; the sign row of a signed multiplier is subtracted.
void MulByMulti(const Multi& a, const Multi& b, Multi& out, Policy p) {
  std::vector<const Word*> rows;
  std::vector<int> shifts;
  std::vector<unsigned char> subs;
  for (int j = 0; j < b.Width(); ++j) {
    rows.push_back(b.Plane(j));
    shifts.push_back(j);
    subs.push_back(b.Format().isSigned && j == b.Width() - 1);
  }
  MulInto(a, rows, shifts, subs, ProductFormat(a.Format(), b.Format()), out, p);
}

}  // namespace

void CheckBool(const Multi& a, const char* what) {
  if (a.Width() != 1)
    throw UserError(
        fmt::format("{} needs a 1-bit multi (a mask), got format {}", what, a.Format().Name()));
}

// ---- Multi ------------------------------------------------------------------------------------

Multi::Multi(Machine& machine, fixed::Format format, std::string name, Uninitialised)
    : machine_(&machine), format_(format) {
  if (!format.IsValid())
    throw UserError(fmt::format("multi '{}': invalid format {}", name, format.Name()));
  alloc_ = machine.Memory().Allocate(name, format.Width(), std::nullopt);
  planes_ = machine.AcquirePlanes(format.Width());
}

Multi::Multi(Machine& machine, fixed::Format format, std::string name, std::optional<Space> space)
    : machine_(&machine), format_(format) {
  if (!format.IsValid())
    throw UserError(fmt::format("multi '{}': invalid format {}", name, format.Name()));
  alloc_ = machine.Memory().Allocate(name, format.Width(), space);
  planes_ = machine.AcquirePlanes(format.Width());
  std::memset(planes_, 0, sizeof(Word) * format.Width() * machine.PlaneStride());
}

Multi::Multi(const Multi& o)
    : Multi(o.GetMachine(), o.format_, o.alloc_.name + "'", Uninitialised{}) {
  machine_->Charge("copy", CopyCost(o.AsOperand(), AsOperand()));
  std::memcpy(planes_, o.planes_, sizeof(Word) * Width() * machine_->PlaneStride());
}

Multi Multi::Constant(Machine& machine, const fixed::Fixed& value) {
  Multi r;
  r.machine_ = &machine;
  r.format_ = value.format;
  r.uni_ = true;
  r.alloc_.name = "uni";
  r.planes_ = machine.AcquirePlanes(r.Width());
  for (int i = 0; i < r.Width(); ++i)
    std::memcpy(r.Plane(i), value.Bit(i) ? machine.OnesPlane() : machine.ZeroPlane(),
                sizeof(Word) * machine.WordsPerPlane());
  return r;
}

Multi::Multi(Multi&& o) noexcept
    : machine_(o.machine_), format_(o.format_), alloc_(o.alloc_), planes_(o.planes_), uni_(o.uni_) {
  o.machine_ = nullptr;
  o.planes_ = nullptr;
}

Multi& Multi::operator=(const Multi& o) {
  if (this == &o) return *this;
  if (Empty()) {
    *this = Multi(o);
    return *this;
  }
  CheckSameMachine(*this, o);
  if (o.format_ != format_) return *this = Convert(o, format_);
  Machine& m = *machine_;
  m.Charge("assign", CopyCost(o.AsOperand(), AsOperand()));
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int i = 0; i < Width(); ++i) {
    pa.push_back(o.Plane(i));
    pb.push_back(Plane(i));
    po.push_back(Plane(i));
  }
  m.Kernels().select(m.Activity(), pa.data(), pb.data(), po.data(), Width(), m.WordsPerPlane());
  return *this;
}

Multi& Multi::operator=(Multi&& o) {
  if (this == &o) return *this;
  if (Empty() || (o.machine_ == machine_ && o.format_ == format_ && machine_->AllActive() &&
                  o.alloc_.space == alloc_.space)) {
    // Outside any where every PE is written: take the value's storage (the compiler
    // would have computed straight into this variable), keeping this name.
    std::string name = alloc_.name;
    bool hadName = !Empty();
    Release();
    machine_ = o.machine_, format_ = o.format_, alloc_ = o.alloc_, planes_ = o.planes_;
    uni_ = o.uni_;
    o.machine_ = nullptr, o.planes_ = nullptr;
    (void)name, (void)hadName;
    return *this;
  }
  return *this = static_cast<const Multi&>(o);
}

Multi::~Multi() { Release(); }

void Multi::Release() {
  if (!machine_) return;
  if (!uni_) machine_->Memory().Free(alloc_.id);
  machine_->ReleasePlanes(planes_, Width());
  machine_ = nullptr;
  planes_ = nullptr;
}

// ---- arithmetic ---------------------------------------------------------------------------

Multi Add(const Multi& a, const Multi& b, Format out, Policy p) {
  CheckSameMachine(a, b);
  Multi r(a.GetMachine(), out, "add", Multi::Uninitialised{});
  a.GetMachine().Charge("add", AddCost(a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  AddInto(a, b, false, r, p);
  return r;
}

Multi Sub(const Multi& a, const Multi& b, Format out, Policy p) {
  CheckSameMachine(a, b);
  Multi r(a.GetMachine(), out, "sub", Multi::Uninitialised{});
  a.GetMachine().Charge("sub", SubCost(a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  AddInto(a, b, true, r, p);
  return r;
}

Multi Neg(const Multi& a, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "neg", Multi::Uninitialised{});
  m.Charge("neg", NegCost(a.AsOperand(), r.AsOperand(), p));
  const Format e = NegFormat(a.Format());
  Scratch exact(m, e.Width());
  NegExact(a, exact.p, e.Width());
  RoundFitInto(m, exact.p, e.Width(), true, e.fracBits, r, p);
  return r;
}

Multi Abs(const Multi& a, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "abs", Multi::Uninitialised{});
  m.Charge("abs", AbsCost(a.AsOperand(), r.AsOperand(), p));
  const Format e = AbsFormat(a.Format());
  if (!a.Format().isSigned) {
    RoundFitInto(m, a.Plane(0), a.Width(), false, a.Format().fracBits, r, p);
    return r;
  }
  const int w = e.Width();  // == NegFormat(a).Width()
  Scratch neg(m, w), exact(m, w);
  NegExact(a, neg.p, w);
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int q = 0; q < w; ++q) {
    pa.push_back(neg.Plane(q));
    pb.push_back(PlaneAt(a, 0, q));
    po.push_back(exact.Plane(q));
  }
  m.Kernels().select(a.Plane(a.Width() - 1), pa.data(), pb.data(), po.data(), w, m.WordsPerPlane());
  RoundFitInto(m, exact.p, w, true, e.fracBits, r, p);
  return r;
}

static Multi MinMax(const Multi& a, const Multi& b, Format out, Policy p, bool isMax) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, out, isMax ? "max" : "min", Multi::Uninitialised{});
  m.Charge(isMax ? "max" : "min", MinMaxCost(a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  Scratch lt(m, 1);
  LessPlane(a, b, lt.p);
  const Format u = UnionFormat(a.Format(), b.Format());
  Scratch exact(m, u.Width());
  if (isMax)
    SelectExact(lt.p, b, a, u, exact.p);
  else
    SelectExact(lt.p, a, b, u, exact.p);
  RoundFitInto(m, exact.p, u.Width(), u.isSigned, u.fracBits, r, p);
  return r;
}

Multi Min(const Multi& a, const Multi& b, Format out, Policy p) {
  return MinMax(a, b, out, p, false);
}
Multi Max(const Multi& a, const Multi& b, Format out, Policy p) {
  return MinMax(a, b, out, p, true);
}

Multi Mul(const Multi& a, const Multi& b, Format out, Policy p) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, out, "mul", Multi::Uninitialised{});
  m.Charge("mul", MulCost(a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  MulByMulti(a, b, r, p);
  return r;
}

Multi Mul(const Multi& a, const Uni& b, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "mulUni", Multi::Uninitialised{});
  m.Charge("mulUni", MulUniCost(a.AsOperand(), b.value, r.AsOperand(), p));
  std::vector<const Word*> rows;
  std::vector<int> shifts;
  std::vector<unsigned char> subs;
  // The machine's schedule (charged above) has a row per one bit of the constant: the
  // controller skips its zero bits. The emulator adds the constant's non-adjacent form
  // instead (NafDigits): the same product with about a third fewer rows on the host.
  for (const auto& [shift, negative] : NafDigits(b.value)) {
    rows.push_back(m.OnesPlane());
    shifts.push_back(shift);
    subs.push_back(negative);
  }
  MulInto(a, rows, shifts, subs, ProductFormat(a.Format(), b.value.format), r, p);
  return r;
}

Multi Add(const Multi& a, const Uni& b, Format out, Policy p) {
  return Add(a, Multi::Constant(a.GetMachine(), b.value), out, p);
}
Multi Add(const Uni& a, const Multi& b, Format out, Policy p) {
  return Add(Multi::Constant(b.GetMachine(), a.value), b, out, p);
}
Multi Sub(const Multi& a, const Uni& b, Format out, Policy p) {
  return Sub(a, Multi::Constant(a.GetMachine(), b.value), out, p);
}
Multi Sub(const Uni& a, const Multi& b, Format out, Policy p) {
  return Sub(Multi::Constant(b.GetMachine(), a.value), b, out, p);
}
Multi Min(const Multi& a, const Uni& b, Format out, Policy p) {
  return Min(a, Multi::Constant(a.GetMachine(), b.value), out, p);
}
Multi Min(const Uni& a, const Multi& b, Format out, Policy p) {
  return Min(Multi::Constant(b.GetMachine(), a.value), b, out, p);
}
Multi Max(const Multi& a, const Uni& b, Format out, Policy p) {
  return Max(a, Multi::Constant(a.GetMachine(), b.value), out, p);
}
Multi Max(const Uni& a, const Multi& b, Format out, Policy p) {
  return Max(Multi::Constant(b.GetMachine(), a.value), b, out, p);
}
Multi Mul(const Uni& a, const Multi& b, Format out, Policy p) { return Mul(b, a, out, p); }
Multi Div(const Multi& a, const Uni& b, Format out, Policy p) {
  return Div(a, Multi::Constant(a.GetMachine(), b.value), out, p);
}
Multi Div(const Uni& a, const Multi& b, Format out, Policy p) {
  return Div(Multi::Constant(b.GetMachine(), a.value), b, out, p);
}

Multi Square(const Multi& a, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "square", Multi::Uninitialised{});
  m.Charge("square", MulCost(a.AsOperand(), a.AsOperand(), r.AsOperand(), p));
  MulByMulti(a, a, r, p);
  return r;
}

// ---- division and square root --------------------------------------------------------------

namespace {

using PlaneList = std::vector<const Word*>;

// |x| into x.Width() scratch planes: 0 - x where the sign is set (|min| fits unsigned).
void MagnitudeInto(const Multi& x, Word* base) {
  Machine& m = x.GetMachine();
  const int w = x.Width();
  NegExact(x, base, w);
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  auto& po = MachineInternals::PointersOut(m);
  pa.clear(), pb.clear(), po.clear();
  for (int q = 0; q < w; ++q) {
    pa.push_back(base + q * m.PlaneStride());
    pb.push_back(x.Plane(q));
    po.push_back(base + q * m.PlaneStride());
  }
  m.Kernels().select(x.Plane(w - 1), pa.data(), pb.data(), po.data(), w, m.WordsPerPlane());
}

}  // namespace

Multi Div(const Multi& a, const Multi& b, Format out, Policy p) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, out, "div", Multi::Uninitialised{});
  m.Charge("div", DivCost(a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  const size_t words = m.WordsPerPlane();
  const PlaneKernels& k = m.Kernels();
  const Format &fa = a.Format(), &fb = b.Format();
  const int wa = a.Width(), wb = b.Width(), wo = r.Width();
  const DivShape s = DivideShape(fa, fb, out, p);
  const int mBits = s.dividendBits, d = s.divisorBits;

  // Magnitudes; the dividend |a|·2^max(shift,0) and divisor |b|·2^max(-shift,0) as planes.
  Scratch magA(m, wa), magB(m, wb);
  if (fa.isSigned) MagnitudeInto(a, magA.p);
  if (fb.isSigned) MagnitudeInto(b, magB.p);
  const int lowA = std::max(s.shift, 0);
  auto dividend = [&](int i) -> const Word* {
    if (i < lowA) return m.ZeroPlane();
    return fa.isSigned ? magA.Plane(i - lowA) : a.Plane(i - lowA);
  };

  // One quotient bit per step, most significant first; the skipped top bits are zero and
  // leave the dividend's top bits as the first partial remainder. One kernel runs every
  // step per vector of PEs (the schedule charged above is unchanged).
  Scratch quo(m, mBits), remPlanes(m, d);
  for (int i = s.steps; i < mBits; ++i) std::memset(quo.Plane(i), 0, sizeof(Word) * words);
  auto& pDividend = MachineInternals::PointersA(m);
  auto& pDivisor = MachineInternals::PointersB(m);
  auto& pOut = MachineInternals::PointersOut(m);
  pDividend.clear(), pDivisor.clear(), pOut.clear();
  for (int i = 0; i < s.steps + s.skipped; ++i) pDividend.push_back(dividend(i));
  pDivisor.assign(d + 1, m.ZeroPlane());
  for (int q = 0; q < wb; ++q)
    pDivisor[s.divisorZeros + q] = fb.isSigned ? magB.Plane(q) : b.Plane(q);
  for (int i = 0; i < s.steps; ++i) pOut.push_back(quo.Plane(i));
  for (int q = 0; q < d; ++q) pOut.push_back(remPlanes.Plane(q));
  const DivideArgs divide{pDividend.data(),
                          pDivisor.data(),
                          d,
                          s.steps,
                          s.skipped,
                          pOut.data(),
                          s.canBeNegative ? pOut.data() + s.steps : nullptr};
  k.divide(divide, words);
  PlaneList rem(d);
  for (int q = 0; q < d; ++q) rem[q] = remPlanes.Plane(q);

  // b == 0 (no overflow is flagged there), then the floor of the signed quotient.
  Scratch flags(m, 4);
  Word* zeroDivisor = flags.Plane(0);
  Word* keep = flags.Plane(1);
  {
    PlaneList bits, zeros(wb, m.ZeroPlane());
    for (int q = 0; q < wb; ++q) bits.push_back(b.Plane(q));
    k.equal(bits.data(), zeros.data(), wb, zeroDivisor, words);
  }
  k.logic(LogicOp::kAndNot, m.Activity(), zeroDivisor, keep, words);
  const Word* signA = fa.isSigned ? a.Plane(wa - 1) : m.ZeroPlane();
  const Word* signB = fb.isSigned ? b.Plane(wb - 1) : m.ZeroPlane();
  if (s.canBeNegative) {
    // Where the signs differ: floor(-Q - frac) = -Q - (R != 0) = ~Q + (R == 0).
    Word* exactRem = flags.Plane(2);
    Word* neg = flags.Plane(3);
    PlaneList zeros(d, m.ZeroPlane());
    k.equal(rem.data(), zeros.data(), d, exactRem, words);
    k.logic(LogicOp::kXor, signA, signB, neg, words);
    const int w = mBits + 1;
    Scratch exact(m, w);
    PlaneList carry(w, m.ZeroPlane()), q(w, m.ZeroPlane());
    carry[0] = exactRem;
    for (int i = 0; i < mBits; ++i) q[i] = quo.Plane(i);
    std::vector<Word*> po(w);
    for (int i = 0; i < w; ++i) po[i] = exact.Plane(i);
    AddArgs args{carry.data(), q.data(), po.data(), w, true, false, 0, false, nullptr, nullptr};
    k.add(args, words);
    k.select(neg, po.data(), q.data(), po.data(), w, words);
    RoundFitInto(m, exact.p, w, true, s.quotient.fracBits, r, p, keep);
  } else {
    RoundFitInto(m, quo.p, mBits, false, s.quotient.fracBits, r, p, keep);
  }

  // Where b == 0: the end of out's range on a's side, and the divideByZero flag.
  Word* notSignA = flags.Plane(2);
  k.logic(LogicOp::kNot, signA, nullptr, notSignA, words);
  PlaneList ends(wo, notSignA);
  if (out.isSigned) ends[wo - 1] = signA;
  std::vector<Word*> ro(wo);
  for (int i = 0; i < wo; ++i) ro[i] = r.Plane(i);
  k.select(zeroDivisor, ends.data(), ro.data(), ro.data(), wo, words);
  k.logic(LogicOp::kAnd, zeroDivisor, m.Activity(), keep, words);
  k.logic(LogicOp::kOr, MachineInternals::DivideByZero(m), keep, MachineInternals::DivideByZero(m),
          words);
  return r;
}

Multi Sqrt(const Multi& a, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "sqrt");
  m.Charge("sqrt", SqrtCost(a.AsOperand(), r.AsOperand(), p));
  const size_t words = m.WordsPerPlane();
  const PlaneKernels& k = m.Kernels();
  const Format& fa = a.Format();
  const SqrtShape s = SquareRootShape(fa, out);
  const int ma = a.Width() - (fa.isSigned ? 1 : 0);
  const int nr = s.rootBits;
  auto radicand = [&](int j) -> const Word* {  // bit j of a's magnitude bits × 2^shift
    const int q = j - s.shift;
    return q >= 0 && q < ma ? a.Plane(q) : m.ZeroPlane();
  };
  const Word* neg = fa.isSigned ? a.Plane(a.Width() - 1) : m.ZeroPlane();
  Scratch keep(m, 1);
  k.logic(LogicOp::kAndNot, m.Activity(), neg, keep.p, words);
  if (nr > 0) {
    // Root bit i: R' = 4R + (radicand bits 2i+1, 2i); if R' >= 4Y + 1, subtract it and
    // set the bit. With j bits decided, R <= 2Y < 2^(j+1), so j+3 positions hold the
    // difference with its sign. One kernel runs every step per vector of PEs.
    Scratch root(m, nr);
    auto& pRadicand = MachineInternals::PointersA(m);
    auto& pRoot = MachineInternals::PointersOut(m);
    pRadicand.clear(), pRoot.clear();
    for (int j = 0; j < 2 * nr; ++j) pRadicand.push_back(radicand(j));
    for (int i = 0; i < nr; ++i) pRoot.push_back(root.Plane(i));
    k.sqrt(SqrtArgs{pRadicand.data(), nr, pRoot.data()}, words);
    RoundFitInto(m, root.p, nr, false, out.fracBits, r, {fixed::Rounding::kFloor, p.overflow},
                 keep.p);
  }
  if (fa.isSigned) {  // a < 0: 0 and the invalid flag
    for (int i = 0; i < r.Width(); ++i)
      k.logic(LogicOp::kAndNot, r.Plane(i), neg, r.Plane(i), words);
    k.logic(LogicOp::kAnd, neg, m.Activity(), keep.p, words);
    k.logic(LogicOp::kOr, MachineInternals::Invalid(m), keep.p, MachineInternals::Invalid(m),
            words);
  }
  return r;
}

Multi Shift(const Multi& a, int k, Format out, Policy p) {
  Machine& m = a.GetMachine();
  Multi r(m, out, "shift", Multi::Uninitialised{});
  m.Charge(k == 0 ? "convert" : "shift", ShiftCost(a.AsOperand(), k, r.AsOperand(), p));
  RoundFitInto(m, a.Plane(0), a.Width(), a.Format().isSigned, a.Format().fracBits - k, r, p);
  return r;
}

Multi Convert(const Multi& a, Format out, Policy p) { return Shift(a, 0, out, p); }

void ConvertUncharged(const Multi& a, Multi& out, Policy p) {
  RoundFitInto(a.GetMachine(), a.Plane(0), a.Width(), a.Format().isSigned, a.Format().fracBits, out,
               p);
}

void SetInvalid(Machine& m, const Word* where) {
  Scratch active(m, 1);
  m.Kernels().logic(LogicOp::kAnd, where, m.Activity(), active.p, m.WordsPerPlane());
  m.Kernels().logic(LogicOp::kOr, MachineInternals::Invalid(m), active.p,
                    MachineInternals::Invalid(m), m.WordsPerPlane());
}

Multi Select(const Multi& mask, const Multi& a, const Multi& b, Format out, Policy p) {
  CheckSameMachine(a, b);
  CheckBool(mask, "Select");
  Machine& m = a.GetMachine();
  Multi r(m, out, "select", Multi::Uninitialised{});
  m.Charge("select", SelectCost(mask.AsOperand(), a.AsOperand(), b.AsOperand(), r.AsOperand(), p));
  const Format u = UnionFormat(a.Format(), b.Format());
  Scratch exact(m, u.Width());
  SelectExact(mask.Plane(0), a, b, u, exact.p);
  RoundFitInto(m, exact.p, u.Width(), u.isSigned, u.fracBits, r, p);
  return r;
}

Multi Broadcast(Machine& m, const fixed::Fixed& value) {
  Multi r(m, value.format, "uni", Multi::Uninitialised{});
  m.Charge("broadcast", BroadcastCost(r.AsOperand()));
  for (int i = 0; i < r.Width(); ++i)
    std::memcpy(r.Plane(i), value.Bit(i) ? m.OnesPlane() : m.ZeroPlane(),
                sizeof(Word) * m.WordsPerPlane());
  return r;
}

// ---- comparisons and logic ----------------------------------------------------------------

Format BoolFormat() { return Format::Unsigned(1, 0); }

Multi Less(const Multi& a, const Multi& b) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, BoolFormat(), "less", Multi::Uninitialised{});
  m.Charge("compare", CompareCost(a.AsOperand(), b.AsOperand(), r.GetSpace()));
  LessPlane(a, b, r.Plane(0));
  return r;
}

Multi LessEqual(const Multi& a, const Multi& b) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, BoolFormat(), "lessEqual", Multi::Uninitialised{});
  m.Charge("compare", CompareCost(a.AsOperand(), b.AsOperand(), r.GetSpace()));
  LessPlane(b, a, r.Plane(0));
  m.Kernels().logic(LogicOp::kNot, r.Plane(0), nullptr, r.Plane(0), m.WordsPerPlane());
  return r;
}

Multi Equal(const Multi& a, const Multi& b) {
  CheckSameMachine(a, b);
  Machine& m = a.GetMachine();
  Multi r(m, BoolFormat(), "equal", Multi::Uninitialised{});
  m.Charge("compare", CompareCost(a.AsOperand(), b.AsOperand(), r.GetSpace()));
  const Format u = UnionFormat(a.Format(), b.Format());
  auto& pa = MachineInternals::PointersA(m);
  auto& pb = MachineInternals::PointersB(m);
  pa.clear(), pb.clear();
  for (int q = 0; q < u.Width(); ++q) {
    pa.push_back(PlaneAt(a, u.fracBits - a.Format().fracBits, q));
    pb.push_back(PlaneAt(b, u.fracBits - b.Format().fracBits, q));
  }
  m.Kernels().equal(pa.data(), pb.data(), u.Width(), r.Plane(0), m.WordsPerPlane());
  return r;
}

Multi Less(const Multi& a, const Uni& b) {
  return Less(a, Multi::Constant(a.GetMachine(), b.value));
}
Multi Less(const Uni& a, const Multi& b) {
  return Less(Multi::Constant(b.GetMachine(), a.value), b);
}
Multi LessEqual(const Multi& a, const Uni& b) {
  return LessEqual(a, Multi::Constant(a.GetMachine(), b.value));
}
Multi LessEqual(const Uni& a, const Multi& b) {
  return LessEqual(Multi::Constant(b.GetMachine(), a.value), b);
}
Multi Equal(const Multi& a, const Uni& b) {
  return Equal(a, Multi::Constant(a.GetMachine(), b.value));
}
Multi Equal(const Uni& a, const Multi& b) {
  return Equal(Multi::Constant(b.GetMachine(), a.value), b);
}

static Multi LogicOf(LogicOp op, const Multi& a, const Multi* b, const char* name) {
  CheckBool(a, name);
  if (b) CheckBool(*b, name), CheckSameMachine(a, *b);
  Machine& m = a.GetMachine();
  Multi r(m, BoolFormat(), name, Multi::Uninitialised{});
  m.Charge("logic", LogicCost(a.AsOperand(), b != nullptr, r.GetSpace()));
  m.Kernels().logic(op, a.Plane(0), b ? b->Plane(0) : nullptr, r.Plane(0), m.WordsPerPlane());
  return r;
}

Multi And(const Multi& a, const Multi& b) { return LogicOf(LogicOp::kAnd, a, &b, "and"); }
Multi Or(const Multi& a, const Multi& b) { return LogicOf(LogicOp::kOr, a, &b, "or"); }
Multi Xor(const Multi& a, const Multi& b) { return LogicOf(LogicOp::kXor, a, &b, "xor"); }
Multi Not(const Multi& a) { return LogicOf(LogicOp::kNot, a, nullptr, "not"); }

Multi operator+(const Multi& a, const Multi& b) {
  return Add(a, b, SumFormat(a.Format(), b.Format()));
}
Multi operator-(const Multi& a, const Multi& b) {
  return Sub(a, b, DiffFormat(a.Format(), b.Format()));
}
Multi operator*(const Multi& a, const Multi& b) {
  return Mul(a, b, ProductFormat(a.Format(), b.Format()));
}
Multi operator-(const Multi& a) { return Neg(a, NegFormat(a.Format())); }
Multi operator+(const Multi& a, const Uni& b) {
  return Add(a, b, SumFormat(a.Format(), b.value.format));
}
Multi operator-(const Multi& a, const Uni& b) {
  return Sub(a, b, DiffFormat(a.Format(), b.value.format));
}
Multi operator*(const Multi& a, const Uni& b) {
  return Mul(a, b, ProductFormat(a.Format(), b.value.format));
}

// ---- where ----------------------------------------------------------------------------------

WhereScope::WhereScope(const Multi& mask) : machine_(&mask.GetMachine()) {
  CheckBool(mask, "where");
  machine_->Charge("where", WhereCost(mask.AsOperand()));
  mask_ = machine_->AcquirePlanes(1);
  std::memcpy(mask_, mask.Plane(0), sizeof(Word) * machine_->WordsPerPlane());
  machine_->PushActivity(mask_, false);
}

void WhereScope::Elsewhere() {
  ZEPHYR_CHECK(!elsewhere_);
  elsewhere_ = true;
  machine_->Charge("elsewhere", ActivityCost());
  machine_->PopActivity();
  machine_->PushActivity(mask_, true);
}

WhereScope::~WhereScope() {
  machine_->Charge("endWhere", ActivityCost());
  machine_->PopActivity();
  machine_->ReleasePlanes(mask_, 1);
}

}  // namespace zephyr::bitserial
