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

// Cycles of one operation of format f on one virtual-PE layer, operands and result in
// `space`, as the engine charges it ("fadd", "fsub", "fmul"); counted by running the
// operation on a one-layer machine of `profile`.
double FloatOpCycles(const MachineProfile& profile, const std::string& op,
                     const fixed::FloatFormat& f, Space space = Space::Internal);

}  // namespace zephyr::bitserial
