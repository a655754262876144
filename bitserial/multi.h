// bitserial/multi.h — the MultiC-like layer: multi (one value per virtual PE) and uni
// (one value on the host), with formats chosen at run time.
//
//   Machine m(Profile("wavetracer"), 384 * 384);
//   Multi t = Mul(a, b, fmt);                     // rounded/fitted like fixed::Mul
//   Multi hit = t < tBest;                        // a 1-bit multi (u1.0)
//   Where(hit, [&] { tBest = t; }).Elsewhere([&] { miss = miss + one; });
//   if (ReduceOr(hit)) ...;  fixed::Fixed nearest = ReduceMin(t);
//
// Every operation is bit-exact with the fixed/ function of the same name (same result
// bits, per-PE overflow flag in the machine (Machine::Overflow); Div and Sqrt also set the
// DivideByZero / Invalid planes) and charges its schedule's
// cycles (bitserial/cost.h) to the machine's report. A new result is computed in every PE;
// assigning into an existing multi (operator=) writes only the active PEs, as MultiC does.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/machine.h"
#include "fixed/format.h"

namespace zephyr::bitserial {

// A host value, as MultiC's uni.
struct Uni {
  fixed::Fixed value;
};

class Multi {
 public:
  Multi() = default;
  // A new variable in PE memory (placed internal if it fits, else external, unless
  // `space` is given); its bits start at zero.
  Multi(Machine& machine, fixed::Format format, std::string name = "multi",
        std::optional<Space> space = std::nullopt);
  // An operation's result, whose kernel writes every bit of every PE: allocated like the
  // above but not zero-filled first (the fill cost as much as a 32-bit add's kernel).
  struct Uninitialised {};
  Multi(Machine& machine, fixed::Format format, std::string name, Uninitialised);
  // A uni value as an operand: its bits are supplied by the controller with each
  // instruction (no PE memory is allocated, reading it costs nothing; Operand::uni). The
  // operations taking a Uni use one; a program would rather Broadcast a value it keeps.
  static Multi Constant(Machine& machine, const fixed::Fixed& value);
  bool IsUni() const { return uni_; }
  Multi(const Multi& other);  // a copy (charged)
  Multi(Multi&& other) noexcept;
  // Assignment writes the active PEs only (converting with the default policy if the
  // formats differ); an empty Multi takes the other's value outright.
  Multi& operator=(const Multi& other);
  Multi& operator=(Multi&& other);
  ~Multi();

  bool Empty() const { return machine_ == nullptr; }
  Machine& GetMachine() const { return *machine_; }
  const fixed::Format& Format() const { return format_; }
  int Width() const { return format_.Width(); }
  Space GetSpace() const { return alloc_.space; }
  const Allocation& GetAllocation() const { return alloc_; }
  Operand AsOperand() const { return {format_, alloc_.space, uni_}; }
  const Word* Plane(int i) const { return planes_ + i * machine_->PlaneStride(); }
  Word* Plane(int i) { return planes_ + i * machine_->PlaneStride(); }

  // Host transfers (charged to the host class): one value per virtual PE, in PE order.
  // Every PE past the vector's end gets 0, whatever the planes held before (Load and
  // LoadRaw clear them first; BitserialPatterns.LoadRawOfAShortListLeavesZeroPastIt).
  // Values must have this multi's format.
  void Load(const std::vector<fixed::Fixed>& values);
  void LoadRaw(const std::vector<int64_t>& raw);  // two's-complement raw integers
  std::vector<fixed::Fixed> Read() const;
  std::vector<int64_t> ReadRaw() const;  // widths <= 64
  // One PE's value, for tests and debugging (not charged).
  fixed::Fixed At(int64_t pe) const;
  bool BitAt(int i, int64_t pe) const { return (Plane(i)[pe >> 6] >> (pe & 63)) & 1; }

 private:
  void Release();
  Machine* machine_ = nullptr;
  fixed::Format format_;
  Allocation alloc_;
  Word* planes_ = nullptr;
  bool uni_ = false;
};

// ---- arithmetic (each as the fixed/ function of the same name) ----------------------------
Multi Add(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Sub(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Neg(const Multi& a, fixed::Format out, fixed::Policy p = {});
Multi Abs(const Multi& a, fixed::Format out, fixed::Policy p = {});
Multi Min(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Max(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Mul(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Mul(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Square(const Multi& a, fixed::Format out, fixed::Policy p = {});
// Uni operands (MultiC mixed uni and multi in every binary operation and comparison): the
// same result as with the uni broadcast into a multi; the uni's bits cost no memory read
// (Operand::uni). Mul(Multi, Uni) below has its own schedule (rows only for one bits).
Multi Add(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Add(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Sub(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Sub(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Min(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Min(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Max(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Max(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Mul(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
Multi Div(const Multi& a, const Uni& b, fixed::Format out, fixed::Policy p = {});
Multi Div(const Uni& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
// Restoring division, one quotient bit per step (docs/bitserial.md). As fixed::Div: the
// exact quotient rounded and fitted; where b == 0 the result is out's largest value if
// a >= 0, its smallest if a < 0, and the PE's DivideByZero flag is set (not Overflow).
Multi Div(const Multi& a, const Multi& b, fixed::Format out, fixed::Policy p = {});
// Restoring square root, one root bit per step. As fixed::Sqrt: the floor of the exact
// root (p.rounding is ignored), fitted with p.overflow; where a < 0 the result is 0 and
// the PE's Invalid flag is set.
Multi Sqrt(const Multi& a, fixed::Format out, fixed::Policy p = {});
Multi Shift(const Multi& a, int k, fixed::Format out, fixed::Policy p = {});
Multi Convert(const Multi& a, fixed::Format out, fixed::Policy p = {});
// mask ? a : b, rounded and fitted to out.
Multi Select(const Multi& mask, const Multi& a, const Multi& b, fixed::Format out,
             fixed::Policy p = {});
// A uni value in every PE (its own format).
Multi Broadcast(Machine& m, const fixed::Fixed& value);

// ---- comparisons and logic: 1-bit multis (u1.0) ------------------------------------------
fixed::Format BoolFormat();
Multi Less(const Multi& a, const Multi& b);
Multi LessEqual(const Multi& a, const Multi& b);
Multi Equal(const Multi& a, const Multi& b);
Multi Less(const Multi& a, const Uni& b);
Multi Less(const Uni& a, const Multi& b);
Multi LessEqual(const Multi& a, const Uni& b);
Multi LessEqual(const Uni& a, const Multi& b);
Multi Equal(const Multi& a, const Uni& b);
Multi Equal(const Uni& a, const Multi& b);
Multi And(const Multi& a, const Multi& b);
Multi Or(const Multi& a, const Multi& b);
Multi Xor(const Multi& a, const Multi& b);
Multi Not(const Multi& a);

// Operators with exact result formats (never overflow): + - * unary-, and comparisons.
Multi operator+(const Multi& a, const Multi& b);
Multi operator-(const Multi& a, const Multi& b);
Multi operator*(const Multi& a, const Multi& b);
Multi operator-(const Multi& a);
inline Multi operator<(const Multi& a, const Multi& b) { return Less(a, b); }
inline Multi operator<=(const Multi& a, const Multi& b) { return LessEqual(a, b); }
inline Multi operator>(const Multi& a, const Multi& b) { return Less(b, a); }
inline Multi operator>=(const Multi& a, const Multi& b) { return LessEqual(b, a); }
inline Multi operator==(const Multi& a, const Multi& b) { return Equal(a, b); }
inline Multi operator&&(const Multi& a, const Multi& b) { return And(a, b); }
inline Multi operator||(const Multi& a, const Multi& b) { return Or(a, b); }
inline Multi operator!(const Multi& a) { return Not(a); }
// With a uni on either side (exact result formats as above).
Multi operator+(const Multi& a, const Uni& b);
Multi operator-(const Multi& a, const Uni& b);
Multi operator*(const Multi& a, const Uni& b);
inline Multi operator<(const Multi& a, const Uni& b) { return Less(a, b); }
inline Multi operator<=(const Multi& a, const Uni& b) { return LessEqual(a, b); }
inline Multi operator>(const Multi& a, const Uni& b) { return Less(b, a); }
inline Multi operator>=(const Multi& a, const Uni& b) { return LessEqual(b, a); }
inline Multi operator==(const Multi& a, const Uni& b) { return Equal(a, b); }

// ---- activity: where / elsewhere ---------------------------------------------------------
// RAII: while a WhereScope lives, only PEs where `mask` (a 1-bit multi) is 1 are active;
// Elsewhere() switches to the PEs of the enclosing activity where it is 0.
class WhereScope {
 public:
  explicit WhereScope(const Multi& mask);
  ~WhereScope();
  void Elsewhere();
  WhereScope(const WhereScope&) = delete;
  WhereScope& operator=(const WhereScope&) = delete;

 private:
  Machine* machine_;
  Word* mask_;
  bool elsewhere_ = false;
};

class WhereClause {
 public:
  WhereClause(const Multi& mask) : mask_(mask) {}
  template <typename F>
  void Elsewhere(F&& body) {
    WhereScope scope(mask_);
    scope.Elsewhere();
    body();
  }

 private:
  const Multi& mask_;
};

template <typename F>
WhereClause Where(const Multi& mask, F&& body) {
  {
    WhereScope scope(mask);
    body();
  }
  return WhereClause(mask);
}

// ---- reductions over the active PEs into a uni ---------------------------------------------
// Or/And/Xor are bitwise over the value's bits; with no active PE they give 0, all ones, 0.
fixed::Fixed ReduceOr(const Multi& a);
fixed::Fixed ReduceAnd(const Multi& a);
fixed::Fixed ReduceXor(const Multi& a);
bool Any(const Multi& mask);  // ReduceOr of a 1-bit multi
// The exact sum, in a format with ceil(log2(virtual PEs)) more integer bits.
fixed::Fixed ReduceSum(const Multi& a);
// With no active PE: Max gives the format's smallest value, Min its largest.
fixed::Fixed ReduceMax(const Multi& a);
fixed::Fixed ReduceMin(const Multi& a);

// ---- mesh communication ---------------------------------------------------------------------
// Each PE takes the value of the PE `distance` steps back along `axis` of the machine's
// shape (x = 0 fastest): out(c) = a(c - distance·e_axis). Edge rule: a PE whose source is
// outside the mesh receives 0 (no wrap-around); every virtual-PE layer is its own mesh.
Multi MeshShift(const Multi& a, int axis, int distance);

// ---- the virtual mesh: MultiC's shapes ------------------------------------------------------
// A shape declared over the machine's virtual PEs (1, 2 or 3 extents, x fastest; virtual PE
// v = x + X·(y + Y·z)); its Size() must be the machine's virtual PEs. The shift moves across
// the whole virtual space: out(c) = a(c - distance·e_axis), 0 where that is outside the
// shape — pixel (x, y) of a 384×384 image goes to (x+1, y) whatever layer holds it.
// Mapping (docs/bitserial.md, "The virtual mesh"): blocks. The physical mesh (the machine's
// shape; for a 1-D shape its PEs as one chain) tiles the virtual one, each physical PE
// holding a b_0 × b_1 (× b_2) block of neighbouring virtual PEs, b_i = V_i / P_i, one per
// layer. A move stays in the PE's memory (another layer) except at the block's edge, where
// it crosses to the neighbouring PE: charged over all layers by VirtualMeshShiftCost.
// UserError: a shape whose size is not the machine's, whose rank differs from the physical
// mesh's (except 1-D) or whose extents are not multiples of it; a layer block (the shift
// needs every layer); an axis outside the shape.
Multi MeshShift(const Multi& a, const MeshShape& shape, int axis, int distance);
// The block extents of `shape` on machine m (b_i above); UserError as MeshShift.
std::vector<int> VirtualBlock(const Machine& m, const MeshShape& shape);

}  // namespace zephyr::bitserial
