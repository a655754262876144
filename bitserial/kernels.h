// bitserial/kernels.h — the wide boolean work on bit-planes, one table per Highway target.
//
// A plane is `words` uint64_t (64 PEs per word; all virtual-PE layers side by side), so one
// kernel call runs an operation over every layer at once. Operands are arrays of plane
// pointers, one per bit position, so alignment, sign extension and zero fill cost nothing:
// a position outside an operand points at the shared zero plane or at the operand's sign
// plane. Kernels are strip-mined: for each vector of PEs the whole bit loop runs with the
// carry in a register (the loop is bound by loads and stores, not by the logic).
//
// Plain scalar types only: the per-target code lives in kernels.cpp (foreach_target.h) and
// the machine picks one table once, when it is built (Kernels()).
#pragma once

#include <cstddef>
#include <cstdint>

namespace zephyr::bitserial {

using Word = uint64_t;

// out[p] = bit p of A + (invertB ? ~B : B) + carryIn, for p < n. A null out[p] is not
// stored. If ovf != null, bits p >= ovfFrom are compared with bit ovfFrom (ovfSigned) or
// with 0 (unsigned) and any difference, ANDed with act, is ORed into *ovf.
struct AddArgs {
  const Word* const* a;
  const Word* const* b;
  Word* const* out;
  int n;
  bool invertB;
  bool carryIn;
  int ovfFrom;
  bool ovfSigned;
  Word* ovf;
  const Word* act;
};

// Steps 2 and 3 of fixed/'s rule on planes. src[i] is exact bit lo+i (i < k, extended with
// zero/sign planes, k >= wo+1 and past the source's sign); roundBit (exact bit lo-1, or
// null) is added for Nearest. out gets wo bits; overflow (ANDed with act) is ORed into ovf;
// Saturate replaces overflowed PEs by the end of the range on the value's side.
struct RoundFitArgs {
  const Word* const* src;
  int k;
  const Word* roundBit;
  Word* const* out;
  int wo;
  bool outSigned;
  bool saturate;
  Word* ovf;
  const Word* act;
};

// Shift-and-add product into out[0..p) (all non-null, distinct from the inputs):
// out = sum over rows r of ±((A & row[r]) << shift[r]) mod 2^p (shift[r] >= 0); a[] has p
// entries (sign- or zero-extended). A row with sub[r] is subtracted (the sign row of a signed
// multiplier). row[r] is the multiplier's plane or the ones plane for a uni constant.
struct MulArgs {
  const Word* const* a;
  int p;
  const Word* const* row;
  const int* shift;
  const unsigned char* sub;
  int rows;
  Word* const* out;
  // If fit is set, out is not used: the product is rounded and fitted as roundFit would
  // with src[i] = product bit fitLo + i (zero below bit 0, bit p-1 repeated above it if
  // productSigned, else zero) and roundBit = bit fitLo - 1 if fitNearest and fitLo > 0.
  const RoundFitArgs* fit = nullptr;
  int fitLo = 0;
  bool productSigned = false;
  bool fitNearest = false;
  // a's own planes: a[0..aBits) (a[aBits..p) only repeat its sign plane or the zero plane),
  // and whether a[aBits-1] is a sign. 0 = all p planes, unsigned (the same product mod 2^p).
  // The kernel then adds rows aBits wide instead of p (Baugh–Wooley; kernels.cpp).
  int aBits = 0;
  bool aSigned = false;
};

// Restoring division, strip-mined: per vector of PEs the partial remainder and divisor stay
// in L1 for every step. rem starts as dividend[steps .. steps+skipped) (zero above); for
// i = steps-1 .. 0: R' = 2R + dividend[i] over d+1 positions, T = R' - divisor (d+1 planes),
// quotient[i] = (T >= 0), R = quotient[i] ? T : R' (low d planes). remainder (d planes, or
// null) gets the final R.
struct DivideArgs {
  const Word* const* dividend;  // at least steps + skipped entries
  const Word* const* divisor;   // d + 1 entries
  int d;
  int steps;
  int skipped;             // <= d
  Word* const* quotient;   // steps entries
  Word* const* remainder;  // d entries, or null
};

// Restoring square root, strip-mined likewise: for root bit i = rootBits-1 .. 0, R' = 4R +
// (radicand[2i+1], radicand[2i]), trial = 4Y + 1 with Y the root bits above i, root[i] =
// (R' >= trial), R = root[i] ? R' - trial : R'.
struct SqrtArgs {
  const Word* const* radicand;  // 2 * rootBits entries
  int rootBits;
  Word* const* root;  // rootBits entries
};

enum class LogicOp : int { kAnd, kOr, kXor, kAndNot /* a & ~b */, kNot /* ~a */ };

struct PlaneKernels {
  const char* target;
  void (*add)(const AddArgs& args, size_t words);
  void (*roundFit)(const RoundFitArgs& args, size_t words);
  void (*mul)(const MulArgs& args, size_t words);
  // out[i] = mask ? a[i] : b[i] for i < n (a bitwise select, never IfVecThenElse).
  void (*select)(const Word* mask, const Word* const* a, const Word* const* b, Word* const* out,
                 int n, size_t words);
  // *out = 1 where a[i] == b[i] for every i < n.
  void (*equal)(const Word* const* a, const Word* const* b, int n, Word* out, size_t words);
  void (*logic)(LogicOp op, const Word* a, const Word* b, Word* out, size_t words);
  void (*divide)(const DivideArgs& args, size_t words);
  void (*sqrt)(const SqrtArgs& args, size_t words);
};

// The table of the best target allowed by hwy (honours hwy::SetSupportedTargetsForTest).
const PlaneKernels& Kernels();

}  // namespace zephyr::bitserial
