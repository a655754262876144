// bitserial/internals.h — what the layers of bitserial/ share beyond the public API: the
// machine's writable per-PE flag planes and kernel-argument arrays, the conversion kernel
// without its charge, the mask check (multi.cpp, reductions.cpp, mesh.cpp, float.cpp). Not for
// programs (they use bitserial/multi.h).
#pragma once

#include <vector>

#include "bitserial/machine.h"
#include "bitserial/multi.h"

namespace zephyr::bitserial {

// The machine's writable flag planes and kernel-argument arrays (private to Machine; the
// operations of bitserial/multi.cpp and bitserial/float.cpp are their only writers).
struct MachineInternals {
  static Word* Overflow(Machine& m) { return m.overflow_; }
  static Word* DivideByZero(Machine& m) { return m.divideByZero_; }
  static Word* Invalid(Machine& m) { return m.invalid_; }
  static std::vector<const Word*>& PointersA(Machine& m) { return m.ptrA_; }
  static std::vector<const Word*>& PointersB(Machine& m) { return m.ptrB_; }
  static std::vector<Word*>& PointersOut(Machine& m) { return m.ptrOut_; }
};

// Convert(a, out.Format(), p) into `out` (overflow flagged in the active PEs) without
// charging it: for an operation whose own schedule includes the conversion's
// (ShiftCost(a, 0, out, p)) and charges it as one operation.
void ConvertUncharged(const Multi& a, Multi& out, fixed::Policy p);

// UserError unless `a` is a 1-bit multi (a mask); `what` names the operation.
void CheckBool(const Multi& a, const char* what);

// Sets the Invalid flag where `where` is 1 in the active PEs.
void SetInvalid(Machine& m, const Word* where);

}  // namespace zephyr::bitserial
