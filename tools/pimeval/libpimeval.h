// libpimeval.h — PIMeval's host API (UVA LavaLab's PIMeval simulator, IISWC 2024) on the
// emulated Zephyr engine: the published PIMbench programs build against this header and the
// archive `make install` puts beside it, unmodified, and run bit-serially on the emulated array
// (docs/pim.md). Written from PIMeval's documented interface (its libpimeval.h at
// github.com/UVA-LavaLab/PIMeval-PIMbench 40ce162: the same names, enumerators in the same
// order, the same signatures); the code behind it is ours (tools/pimeval/pimeval.cpp).
//
// Standalone C++17: a client compiles it with `g++ -std=c++17` and includes nothing of the
// engine. Every call returns PIM_OK, or PIM_ERROR (an object id of -1) after printing on
// stderr a line "PIM-Error: <call>: <what is wrong>"; an unsupported call, type, device or
// layout is such an error naming it, never a silently wrong result.
#ifndef ZEPHYR_LIBPIMEVAL_H
#define ZEPHYR_LIBPIMEVAL_H

#include <cstdarg>
#include <cstdint>
#include <functional>
#include <vector>

// A call's outcome.
enum PimStatus {
  PIM_ERROR = 0,
  PIM_OK,
};

// The device kinds PIMeval names. Run here: PIM_FUNCTIONAL, PIM_DEVICE_BITSIMD_V and
// PIM_DEVICE_BITSIMD_V_AP, on the BitSIMD-V machine profile (or ZEPHYR_MACHINE's). Refused,
// naming what would be needed: the other bit-serial designs (their micro-op costs as a
// profile) and the bit-parallel ones (BITSIMD_H, FULCRUM, BANK_LEVEL, AQUABOLT, AIM: a
// word-parallel engine).
enum PimDeviceEnum {
  PIM_DEVICE_NONE = 0,
  PIM_FUNCTIONAL,
  PIM_DEVICE_BITSIMD_V,
  PIM_DEVICE_BITSIMD_V_NAND,
  PIM_DEVICE_BITSIMD_V_MAJ,
  PIM_DEVICE_BITSIMD_V_AP,
  PIM_DEVICE_DRISA_NOR,
  PIM_DEVICE_DRISA_MIXED,
  PIM_DEVICE_SIMDRAM,
  PIM_DEVICE_BITSIMD_H,
  PIM_DEVICE_FULCRUM,
  PIM_DEVICE_BANK_LEVEL,
  PIM_DEVICE_AQUABOLT,
  PIM_DEVICE_AIM,
};

// The memory protocol of a device's memory file (a config's memory_config_file).
enum PimDeviceProtocolEnum {
  PIM_DEVICE_PROTOCOL_DDR = 0,
  PIM_DEVICE_PROTOCOL_LPDDR,
  PIM_DEVICE_PROTOCOL_HBM,
  PIM_DEVICE_PROTOCOL_GDDR,
};

// Object layouts: AUTO, V and V1 are the vertical (bit-serial) layout, one element per
// column, its bits down the rows. H and H1 (an element across its bits' columns of one row) are
// accepted as PIMeval's BitSIMD model accepts them: the same results, computed bit-serially,
// the device counted as columns / bits-per-element columns (PIMeval's extra passes; docs/pim.md).
// V1 and H1 refuse an object that needs more than one region per core.
enum PimAllocEnum {
  PIM_ALLOC_AUTO = 0,
  PIM_ALLOC_V,
  PIM_ALLOC_H,
  PIM_ALLOC_V1,
  PIM_ALLOC_H1,
};

// Copy layouts of the ...WithType copies: both are the plain copy (PIMeval does not use it).
enum PimCopyEnum {
  PIM_COPY_V,
  PIM_COPY_H,
};

// Element types. Supported: PIM_BOOL (one bit; one uint8_t per element on the host, its
// lowest bit), PIM_INT8..64 and PIM_UINT8..64 (two's complement / unsigned, wrapping as C++'s
// fixed-width arithmetic), PIM_FP32 (IEEE binary32, one float per element on the host; the
// engine's bit-serial MultiFloat, round to nearest even). Refused: PIM_FP16, PIM_BF16, PIM_FP8.
enum PimDataType {
  PIM_BOOL = 0,
  PIM_INT8,
  PIM_INT16,
  PIM_INT32,
  PIM_INT64,
  PIM_UINT8,
  PIM_UINT16,
  PIM_UINT32,
  PIM_UINT64,
  PIM_FP32,
  PIM_FP16,
  PIM_BF16,
  PIM_FP8,
};

// What pimGetDeviceProperties reports: the device as created (counts of each part;
// numPIMCores = ranks x banks x subarrays, a subarray being one bit-serial core of
// numColPerSubarray one-bit PEs); isHLayoutDevice is always false (vertical layout).
struct PimDeviceProperties {
  PimDeviceEnum deviceType = PIM_DEVICE_NONE;
  PimDeviceEnum simTarget = PIM_DEVICE_NONE;
  unsigned numRanks = 0;
  unsigned numBankPerRank = 0;
  unsigned numSubarrayPerBank = 0;
  unsigned numRowPerSubarray = 0;
  unsigned numColPerSubarray = 0;
  unsigned numPIMCores = 0;
  bool isHLayoutDevice = false;
};

typedef int PimCoreId;
typedef int PimObjId;  // an object's id; -1 for a failed allocation

// ---- statistics ----------------------------------------------------------------------------
// Host wall time between start and end is reported by pimShowStats (PIMeval uses it for its
// refresh model; it is not added to the modelled time here).
void pimStartTimer();
void pimEndTimer();
// Prints the per-call table (calls, modelled ms) with the host<->device copies, then the
// engine's cycle report (by class and operation) of each set of associated objects and the
// machine profile; with ZEPHYR_REPORT=FILE also writes them as JSON to FILE.
void pimShowStats();
void pimResetStats();  // zeroes the table and the cycle reports
bool pimIsAnalysisMode();  // always false: every call computes its results

// ---- the device ----------------------------------------------------------------------------
// Creates the device (one at a time): numRanks x numBankPerRank x numSubarrayPerBank subarrays
// of numCols one-bit PEs each, numRows bits of memory per PE. bufferSize (AiM only) must be 0.
// ZEPHYR_MACHINE=NAME|FILE runs on that machine profile instead (wavetracer, mpp, blitzen, a
// profile file).
PimStatus pimCreateDevice(PimDeviceEnum deviceType, unsigned numRanks, unsigned numBankPerRank,
                          unsigned numSubarrayPerBank, unsigned numRows, unsigned numCols,
                          unsigned bufferSize = 0);
// The same from a PIMeval .cfg file (key = value lines; ';' starts a comment): num_ranks,
// num_bank_per_rank, num_subarray_per_bank, num_row_per_subarray, num_col_per_subarray,
// simulation_target (used when deviceType is PIM_FUNCTIONAL), memory_config_file (a .ini beside
// it whose tCK, tRAS, tRP and tCCD_S set the profile's timings), max_num_threads, buffer_size.
// Errors name FILE:LINE.
PimStatus pimCreateDeviceFromConfig(PimDeviceEnum deviceType, const char* configFileName);
PimStatus pimGetDeviceProperties(PimDeviceProperties* deviceProperties);
PimStatus pimDeleteDevice();  // frees every object; statistics are kept until the next device

// ---- objects -------------------------------------------------------------------------------
// numElements elements of dataType, one per PE column. Allocations of the same shape share
// PEs only through pimAllocAssociated; operands of every operation must be associated.
PimObjId pimAlloc(PimAllocEnum allocType, uint64_t numElements, PimDataType dataType);
PimObjId pimAllocAssociated(PimObjId assocId, PimDataType dataType);
// AiM's global buffer: refused, as PIMeval refuses it on every target but PIM_DEVICE_AIM.
PimObjId pimAllocBuffer(uint32_t numElements, PimDataType dataType);
PimStatus pimFree(PimObjId obj);

// ---- copies --------------------------------------------------------------------------------
// Element range [idxBegin, idxEnd); 0, 0 means the whole object. The host side holds
// idxEnd - idxBegin elements of the object's C type (uint8_t for PIM_BOOL).
PimStatus pimCopyHostToDevice(void* src, PimObjId dest, uint64_t idxBegin = 0,
                              uint64_t idxEnd = 0);
PimStatus pimCopyDeviceToHost(PimObjId src, void* dest, uint64_t idxBegin = 0,
                              uint64_t idxEnd = 0);
PimStatus pimCopyDeviceToDevice(PimObjId src, PimObjId dest, uint64_t idxBegin = 0,
                                uint64_t idxEnd = 0);
PimStatus pimCopyObjectToObject(PimObjId src, PimObjId dest);
// Element-wise conversion between integer types (value wrapped into dest's type, as a C++ cast);
// from or to PIM_FP32 refused (PIMeval leaves it unimplemented).
PimStatus pimConvertType(PimObjId src, PimObjId dest);

// ---- element-wise arithmetic and logic (operands associated, of one type) ------------------
// Results wrap to the type's width as C++'s fixed-width integers do; pimAdd/pimSub also take
// a PIM_BOOL src2. Division truncates toward zero; a zero divisor anywhere is PIM_ERROR with
// dest unchanged (PIMeval's "Division by zero"). On PIM_FP32: the C++ float operation on each
// element (NaN results canonical 0x7fc00000); pimMin/pimMax are (a < b) ? a : b and
// (a > b) ? a : b, pimAbs a < 0 ? -a : a; the bitwise calls are refused.
PimStatus pimAdd(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimSub(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimMul(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimDiv(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimAbs(PimObjId src, PimObjId dest);
PimStatus pimNot(PimObjId src, PimObjId dest);
PimStatus pimAnd(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimOr(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimXor(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimXnor(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimMin(PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimMax(PimObjId src1, PimObjId src2, PimObjId dest);
// The scalar is a 64-bit value (int64_t for signed types): the result is the C++ operation on
// the element widened to 64 bits and the scalar, wrapped to the element's type. On PIM_FP32 the
// scalar's low 32 bits are the float's pattern; pimMinScalar/pimMaxScalar are std::min/std::max.
PimStatus pimAddScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimSubScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimMulScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimDivScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimAndScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimOrScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimXorScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimXnorScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimMinScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);
PimStatus pimMaxScalar(PimObjId src, PimObjId dest, uint64_t scalarValue);

// Comparisons into a PIM_BOOL object (1 where true).
PimStatus pimGT(PimObjId src1, PimObjId src2, PimObjId destBool);
PimStatus pimLT(PimObjId src1, PimObjId src2, PimObjId destBool);
PimStatus pimEQ(PimObjId src1, PimObjId src2, PimObjId destBool);
PimStatus pimNE(PimObjId src1, PimObjId src2, PimObjId destBool);
PimStatus pimGTScalar(PimObjId src, PimObjId destBool, uint64_t scalarValue);
PimStatus pimLTScalar(PimObjId src, PimObjId destBool, uint64_t scalarValue);
PimStatus pimEQScalar(PimObjId src, PimObjId destBool, uint64_t scalarValue);
PimStatus pimNEScalar(PimObjId src, PimObjId destBool, uint64_t scalarValue);

// dest = src1 * scalarValue + src2, wrapped.
PimStatus pimScaledAdd(PimObjId src1, PimObjId src2, PimObjId dest, uint64_t scalarValue);
// dest = the number of one bits of each element (same type as src).
PimStatus pimPopCount(PimObjId src, PimObjId dest);
// Inclusive prefix sum along the elements, wrapped (all elements within one layer of PEs);
// refused on PIM_FP32 (PIMeval's element-by-element float order is not reproduced).
PimStatus pimPrefixSum(PimObjId src, PimObjId dest);
// AiM's per-core multiply-accumulate over the global buffer: refused, as PIMeval refuses it on
// every target but PIM_DEVICE_AIM.
PimStatus pimMAC(PimObjId src1, PimObjId src2, void* dest);

// Reductions over [idxBegin, idxEnd) (idxEnd 0: to the end; idxBegin == idxEnd != 0: empty).
// As PIMeval, they fold into what *sum / *min / *max already holds: pimRedSum ADDS the range's
// sum to an int64_t (signed types) or uint64_t (unsigned, PIM_BOOL); pimRedMin/Max keep the
// smaller/larger of the object's C type value at *min/*max and the range's extreme. PIM_FP32:
// a float at *sum/*min/*max; min/max pick PIMeval's element (first of the extremes, NaN skipped,
// seeded with FLT_MAX / -FLT_MAX); the sum adds pairwise by element index (docs/pim.md).
PimStatus pimRedSum(PimObjId src, void* sum, uint64_t idxBegin = 0, uint64_t idxEnd = 0);
PimStatus pimRedMin(PimObjId src, void* min, uint64_t idxBegin = 0, uint64_t idxEnd = 0);
PimStatus pimRedMax(PimObjId src, void* max, uint64_t idxBegin = 0, uint64_t idxEnd = 0);

// Bit bitIdx (0 = least significant) of each element into / from a PIM_BOOL object.
PimStatus pimBitSliceExtract(PimObjId src, PimObjId destBool, unsigned bitIdx);
PimStatus pimBitSliceInsert(PimObjId srcBool, PimObjId dest, unsigned bitIdx);
// dest[i] = cond ? src[i] : dest[i];  cond ? scalar : dest[i];  cond ? src1[i] : src2[i];
// cond ? src1[i] : scalar. The scalar's low bits of the element's width are used.
PimStatus pimCondCopy(PimObjId condBool, PimObjId src, PimObjId dest);
PimStatus pimCondBroadcast(PimObjId condBool, uint64_t scalarBits, PimObjId dest);
PimStatus pimCondSelect(PimObjId condBool, PimObjId src1, PimObjId src2, PimObjId dest);
PimStatus pimCondSelectScalar(PimObjId condBool, PimObjId src1, uint64_t scalarBits,
                              PimObjId dest);

// Every element = value wrapped to the type; pimBroadcastFP writes the float's bit pattern (into
// an integer object its low bits), as PIMeval's.
PimStatus pimBroadcastInt(PimObjId dest, int64_t value);
PimStatus pimBroadcastUInt(PimObjId dest, uint64_t value);
PimStatus pimBroadcastFP(PimObjId dest, float value);
// In place, by one element: Right moves element i to i+1, Left i+1 to i; a rotate brings the
// element pushed off one end in at the other, a shift brings in 0.
PimStatus pimRotateElementsRight(PimObjId src);
PimStatus pimRotateElementsLeft(PimObjId src);
PimStatus pimShiftElementsRight(PimObjId src);
PimStatus pimShiftElementsLeft(PimObjId src);
// Bit shifts of each element: right is arithmetic for signed types, logical for unsigned; a
// shift by the width or more gives 0 (left, unsigned right) or the sign (signed right).
PimStatus pimShiftBitsRight(PimObjId src, PimObjId dest, unsigned shiftAmount);
PimStatus pimShiftBitsLeft(PimObjId src, PimObjId dest, unsigned shiftAmount);

// dest[i] = lut[src[i]] for PIM_UINT8 objects, lut of 256 entries (the S-box or its inverse,
// as the caller supplies), looked up on the array.
PimStatus pimAesSbox(PimObjId src, PimObjId dest, const std::vector<uint8_t>& lut);
PimStatus pimAesInverseSbox(PimObjId src, PimObjId dest, const std::vector<uint8_t>& lut);

// A list of calls run in order by pimFuse (PIMeval's experimental fusion; no fusion here: the
// same results and charges as the calls one by one). Stops at the first error.
struct PimProg {
  template <typename... Args>
  void add(PimStatus (*api)(Args...), Args... args) {
    m_apis.push_back([=]() { return api(args...); });
  }
  std::vector<std::function<PimStatus()>> m_apis;
};
PimStatus pimFuse(PimProg prog);

// ---- calls PIMeval marks as architecture-dependent -----------------------------------------
// PIM_COPY_V and PIM_COPY_H are the plain copy (PIMeval's copies ignore the type).
PimStatus pimCopyHostToDeviceWithType(PimCopyEnum copyType, void* src, PimObjId dest,
                                      uint64_t idxBegin = 0, uint64_t idxEnd = 0);
PimStatus pimCopyDeviceToHostWithType(PimCopyEnum copyType, PimObjId src, void* dest,
                                      uint64_t idxBegin = 0, uint64_t idxEnd = 0);
// Refused (-1): references to an object's negation or range.
PimObjId pimCreateDualContactRef(PimObjId refId);
PimObjId pimCreateRangedRef(PimObjId refId, uint64_t idxBegin, uint64_t idxEnd);

// BitSIMD-V / SIMDRAM micro-op programming: declared so programs link; every call is refused
// (PIM_ERROR): programs here are written with the operations above.
enum PimRowReg {
  PIM_RREG_NONE = 0,
  PIM_RREG_SA,
  PIM_RREG_R1,
  PIM_RREG_R2,
  PIM_RREG_R3,
  PIM_RREG_R4,
  PIM_RREG_R5,
  PIM_RREG_R6,
  PIM_RREG_R7,
  PIM_RREG_R8,
  PIM_RREG_R9,
  PIM_RREG_R10,
  PIM_RREG_R11,
  PIM_RREG_R12,
  PIM_RREG_R13,
  PIM_RREG_R14,
  PIM_RREG_R15,
  PIM_RREG_R16,
  PIM_RREG_MAX
};
PimStatus pimOpReadRowToSa(PimObjId src, unsigned ofst);
PimStatus pimOpWriteSaToRow(PimObjId src, unsigned ofst);
PimStatus pimOpTRA(PimObjId src1, unsigned ofst1, PimObjId src2, unsigned ofst2, PimObjId src3,
                   unsigned ofst3);
PimStatus pimOpMove(PimObjId objId, PimRowReg src, PimRowReg dest);
PimStatus pimOpSet(PimObjId objId, PimRowReg src, bool val);
PimStatus pimOpNot(PimObjId objId, PimRowReg src, PimRowReg dest);
PimStatus pimOpAnd(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpOr(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpNand(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpNor(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpXor(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpXnor(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg dest);
PimStatus pimOpMaj(PimObjId objId, PimRowReg src1, PimRowReg src2, PimRowReg src3,
                   PimRowReg dest);
PimStatus pimOpSel(PimObjId objId, PimRowReg cond, PimRowReg src1, PimRowReg src2,
                   PimRowReg dest);
PimStatus pimOpRotateRH(PimObjId objId, PimRowReg src);
PimStatus pimOpRotateLH(PimObjId objId, PimRowReg src);
PimStatus pimOpAP(int numSrc, ...);
PimStatus pimOpAAP(int numSrc, int numDest, ...);

#endif  // ZEPHYR_LIBPIMEVAL_H
