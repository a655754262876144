// bitserial/cost.h — the micro-op schedule of every operation, as counts.
//
// Each function walks the bit positions the serial algorithm visits and counts the
// micro-ops a PE executes for ONE virtual-PE layer (docs/bitserial.md gives the closed
// forms). The engine charges these counts × the profile's costs × the number of layers;
// `zephyr cycles` prints them. Counts depend only on formats, places and the policy
// (and, for multiply by a uni constant, on the constant's bits), never on the data.
// The float operations are counted the second way, as they run: bitserial/serial.h.
#pragma once

#include <array>
#include <cstdint>

#include "bitserial/memory.h"   // Space
#include "bitserial/profile.h"  // MicroOp, MicroOpCounts
#include "fixed/format.h"

namespace zephyr::bitserial {

// An operand as the schedule sees it: its format and where it lives.
// A uni operand (`uni`) is a host value whose bits the controller supplies with each
// instruction, as the multiplier bits of a multiply by a uni constant: reading one costs
// nothing, and what the host knows of it (its sign, whether it is 0) costs no pass.
struct Operand {
  fixed::Format format;
  Space space = Space::kInternal;
  bool uni = false;
};

// The exact-result formats (docs/bitserial.md, "How the engine works", exactness).
fixed::Format SumFormat(const fixed::Format& a, const fixed::Format& b);   // a + b
fixed::Format DiffFormat(const fixed::Format& a, const fixed::Format& b);  // a - b
fixed::Format ProductFormat(const fixed::Format& a, const fixed::Format& b);
fixed::Format NegFormat(const fixed::Format& a);
fixed::Format AbsFormat(const fixed::Format& a);
fixed::Format UnionFormat(const fixed::Format& a, const fixed::Format& b);  // holds both

MicroOpCounts AddCost(Operand a, Operand b, Operand out, fixed::Policy p);
MicroOpCounts SubCost(Operand a, Operand b, Operand out, fixed::Policy p);
MicroOpCounts NegCost(Operand a, Operand out, fixed::Policy p);
MicroOpCounts AbsCost(Operand a, Operand out, fixed::Policy p);
// a × 2^k rounded and fitted (Convert is k = 0).
MicroOpCounts ShiftCost(Operand a, int k, Operand out, fixed::Policy p);
// <, <=, ==: one result bit written to `outSpace`.
MicroOpCounts CompareCost(Operand a, Operand b, Space outSpace);
MicroOpCounts SelectCost(Operand mask, Operand a, Operand b, Operand out, fixed::Policy p);
MicroOpCounts MinMaxCost(Operand a, Operand b, Operand out, fixed::Policy p);
MicroOpCounts MulCost(Operand a, Operand b, Operand out, fixed::Policy p);
// Rows only for the constant's one bits (the controller skips zero bits).
MicroOpCounts MulUniCost(Operand a, const fixed::Fixed& c, Operand out, fixed::Policy p);
// Restoring division (docs/bitserial.md, "The schedules", Divide): the shape of the
// divider, shared by the engine and its schedule. The quotient is floor(|a|·2^shift / |b|)
// (shift = fb + fo - fa, one more for Nearest), sign-corrected to the floor of the signed
// quotient, then rounded (Nearest: the extra bit) and fitted like every other result.
struct DivShape {
  int shift;               // the quotient's scale (see above)
  int dividendBits;        // m: planes of |a|·2^max(shift, 0) (the low max(shift, 0) are zero)
  int divisorZeros;        // max(-shift, 0): zero low planes of the scaled divisor
  int divisorBits;         // d = width of b + divisorZeros (the partial remainder has d bits)
  int skipped;             // leading quotient bits known to be zero: min(divisorZeros, m)
  int steps;               // quotient bits computed, one subtract-and-restore each: m - skipped
  bool canBeNegative;      // a or b signed: the magnitude quotient needs the floor correction
  fixed::Format quotient;  // the exact floor quotient (fo + Nearest fraction bits)
};
DivShape DivideShape(const fixed::Format& a, const fixed::Format& b, const fixed::Format& out,
                     fixed::Policy p);
// Restoring square root of a's non-negative bits scaled by 2^shift (shift = 2·fo - fa).
struct SqrtShape {
  int shift;
  int radicandBits;  // max(0, magnitude bits of a + shift)
  int rootBits;      // ceil(radicandBits / 2): one subtract-and-restore step each
};
SqrtShape SquareRootShape(const fixed::Format& a, const fixed::Format& out);
MicroOpCounts DivCost(Operand a, Operand b, Operand out, fixed::Policy p);
// Sqrt always rounds down (fixed::Sqrt); only p.overflow matters.
MicroOpCounts SqrtCost(Operand a, Operand out, fixed::Policy p);
MicroOpCounts LogicCost(Operand a, bool binary, Space outSpace);  // 1-bit and/or/xor/not
MicroOpCounts CopyCost(Operand a, Operand out);                   // masked assignment
MicroOpCounts BroadcastCost(Operand out);                         // a uni value into every PE
MicroOpCounts HostTransferCost(int width);                        // planes between host and array
enum class ReduceKind { kOr, kAnd, kXor, kSum, kMax, kMin };
const char* ReduceName(ReduceKind k);
MicroOpCounts ReduceCost(ReduceKind kind, Operand a);
MicroOpCounts MeshShiftCost(Operand a, int distance);
// A shift by `distance` along an axis of the virtual mesh (multi.h) with the block mapping:
// each physical PE holds `layers` virtual PEs, `block` of them along the axis. Summed over
// every layer: each layer's w bits are read and written once (from another layer of the
// same PE's memory, or from a neighbouring PE), and w·|distance|·layers/block bits cross
// the physical mesh (docs/bitserial.md, "The virtual mesh").
MicroOpCounts VirtualMeshShiftCost(Operand a, int layers, int block, int distance);
MicroOpCounts WhereCost(Operand mask);  // read the mask, load the activity flag
MicroOpCounts ActivityCost();           // elsewhere / end of scope: one activity load

}  // namespace zephyr::bitserial
