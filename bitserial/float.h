// bitserial/float.h — MultiC's `multi float`: floating point done bit-serially by the PEs,
// with a run-time format (fixed/float.h: exponent and significand bits, subnormals or
// flush-to-zero).
//
//   Machine m(Profile("mpp"));
//   MultiFloat a(m, FloatFormat::Binary32(), "a"), b(...);
//   MultiFloat c = Add(a, b);            // IEEE round-to-nearest-even, bit-exact with
//   Multi lt = Less(a, c);               //   fixed::FloatAdd, fixed::FloatLess, ...
//
// Every operation is a schedule of the same bit-serial passes as the fixed-point layer
// (docs/float.md): exponent differences by serial subtraction, the data-dependent
// alignment and normalisation shifts as log2 stages of masked moves (one stage per bit of
// the shift amount, so the cycle count never depends on the data), round-to-nearest-even
// by one serial increment of the packed exponent and fraction. The micro-ops are counted
// as the passes run and charged once per operation ("fadd", "fmul", ...); the working
// significand lives in the accumulator (the MPP's shift register, Batcher 1980), the rest
// in internal memory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/float.h"

namespace zephyr::bitserial {

class MultiFloat {
 public:
  MultiFloat() = default;
  // A new float variable in PE memory (1 + expBits + fracBits bits, +0 in every PE);
  // throws UserError for an invalid format.
  MultiFloat(Machine& machine, fixed::FloatFormat format, std::string name = "float",
             std::optional<Space> space = std::nullopt);
  bool Empty() const { return bits_.Empty(); }
  Machine& GetMachine() const { return bits_.GetMachine(); }
  const fixed::FloatFormat& Format() const { return format_; }
  // The bit pattern (sign, exponent, fraction) as an unsigned multi: plane i = bit i.
  const Multi& Bits() const { return bits_; }
  Multi& Bits() { return bits_; }
  // Host transfers (charged): one bit pattern per virtual PE, PEs past the end get +0.
  void Load(const std::vector<uint64_t>& bits);
  std::vector<uint64_t> Read() const;
  uint64_t At(int64_t pe) const;  // not charged (tests, debugging)

 private:
  friend MultiFloat WrapFloat(Multi bits, const fixed::FloatFormat& f);
  fixed::FloatFormat format_;
  Multi bits_;
};

// A host float, MultiC's uni float: a bit pattern of its format.
struct UniFloat {
  fixed::FloatFormat format;
  uint64_t bits = 0;
};
// The uni value in every PE (charged as a broadcast).
MultiFloat Broadcast(Machine& m, const UniFloat& value);

// Arithmetic: both operands must have the same format (UserError otherwise); the result
// has it too. Each equals the fixed/float.h function of the same name in every PE.
MultiFloat Add(const MultiFloat& a, const MultiFloat& b);
MultiFloat Sub(const MultiFloat& a, const MultiFloat& b);
MultiFloat Mul(const MultiFloat& a, const MultiFloat& b);
// Restoring division of the significands, one quotient bit per step (p + 2 of them).
MultiFloat Div(const MultiFloat& a, const MultiFloat& b);
// Restoring square root of the significand, one root bit per step (p + 2 of them).
MultiFloat Sqrt(const MultiFloat& a);
// IEEE 754-2019 minimumNumber / maximumNumber (a NaN operand yields the other; -0 < +0).
MultiFloat Min(const MultiFloat& a, const MultiFloat& b);
MultiFloat Max(const MultiFloat& a, const MultiFloat& b);

// IEEE comparisons as 1-bit multis (u1.0): false where either operand is NaN; -0 == +0.
// All three are charged as "fcompare".
Multi Less(const MultiFloat& a, const MultiFloat& b);
Multi LessEqual(const MultiFloat& a, const MultiFloat& b);
Multi Equal(const MultiFloat& a, const MultiFloat& b);

// Conversions (fixed::FloatFromFixed / FloatToFixed). ToFloat: a fixed-point multi's exact
// value rounded once to f ("ffromfixed"). ToFixed: the float's exact value rounded and
// fitted into `out` as fixed::Convert does (overflow flagged in the active PEs); NaN gives
// 0 and sets the Invalid flag, ±inf out's largest / smallest value with the Overflow flag
// ("ftofixed"). ToFixed throws UserError if out.Width() + precision + 3 > 128.
MultiFloat ToFloat(const Multi& a, const fixed::FloatFormat& f);
Multi ToFixed(const MultiFloat& a, fixed::Format out, fixed::Policy p = {});

// A uni float on either side of every binary operation and comparison: the same result as
// with the uni broadcast, its bits supplied by the controller (free to read, as
// Operand::uni; the passes over them still run).
MultiFloat Add(const MultiFloat& a, const UniFloat& b);
MultiFloat Add(const UniFloat& a, const MultiFloat& b);
MultiFloat Sub(const MultiFloat& a, const UniFloat& b);
MultiFloat Sub(const UniFloat& a, const MultiFloat& b);
MultiFloat Mul(const MultiFloat& a, const UniFloat& b);
MultiFloat Mul(const UniFloat& a, const MultiFloat& b);
MultiFloat Div(const MultiFloat& a, const UniFloat& b);
MultiFloat Div(const UniFloat& a, const MultiFloat& b);
MultiFloat Min(const MultiFloat& a, const UniFloat& b);
MultiFloat Min(const UniFloat& a, const MultiFloat& b);
MultiFloat Max(const MultiFloat& a, const UniFloat& b);
MultiFloat Max(const UniFloat& a, const MultiFloat& b);
Multi Less(const MultiFloat& a, const UniFloat& b);
Multi Less(const UniFloat& a, const MultiFloat& b);
Multi LessEqual(const MultiFloat& a, const UniFloat& b);
Multi LessEqual(const UniFloat& a, const MultiFloat& b);
Multi Equal(const MultiFloat& a, const UniFloat& b);
Multi Equal(const UniFloat& a, const MultiFloat& b);

// The float operations `FloatOpCycles` and `zephyr cycles --op` know, each charged under
// its own name: fadd fsub fmul fdiv fsqrt fmin fmax fcompare (Less) ftofixed ffromfixed.
const std::vector<std::string>& FloatOpNames();
// Cycles of one operation of format f on one virtual-PE layer, operands and result in
// `space`, as the engine charges it; counted by running the operation on a one-layer
// machine of `profile`. The conversions take the fixed side's format and policy from
// `fixedSide` and `policy`. UserError for an unknown op.
double FloatOpCycles(const MachineProfile& profile, const std::string& op,
                     const fixed::FloatFormat& f, Space space = Space::kInternal,
                     fixed::Format fixedSide = fixed::Format::Signed(15, 16),
                     fixed::Policy policy = {});
// The same run's whole cycle report (the op's micro-ops by class).
CycleReport FloatOpReport(const MachineProfile& profile, const std::string& op,
                          const fixed::FloatFormat& f, Space space = Space::kInternal,
                          fixed::Format fixedSide = fixed::Format::Signed(15, 16),
                          fixed::Policy policy = {});

}  // namespace zephyr::bitserial
