// bitserial/profile.h — machine profiles: the geometry and the cycle cost of every micro-op.
//
// Machine timing is data, not code (as a memory simulator keeps its DRAM presets): a profile is a
// named table of micro-op costs plus the machine's geometry and clock. The engine never
// special-cases a machine; the MPP's published figures (Batcher 1980) fall out of the same
// schedules as the WaveTracer's, with different numbers in the table. Any entry can be overridden
// at run time ("name=value"); a profile with a missing entry is rejected naming it.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace zephyr::bitserial {

// The micro-ops of a 1-bit PE datapath (docs/bitserial.md, "Micro-ops").
enum class MicroOp : int {
  kReadInternal,   // read one bit of internal PE memory into the ALU
  kWriteInternal,  // write one ALU output bit to internal memory (gated by activity)
  kReadExternal,   // the same for external PE memory
  kWriteExternal,
  kAluStep,           // one boolean / full-adder step (sum + carry flag, or a logic op)
  kFlagOp,            // clear/set/latch a PE flag (carry, mask register, overflow latch)
  kAccumulatorRead,   // read a bit of the multiply partial-product accumulator
  kAccumulatorWrite,  // write a bit of it (MPP: a shift register; WaveTracer: memory)
  kActivitySet,       // load/set/clear the activity flag (where / elsewhere)
  kMeshHop,           // move one bit-plane one PE along a mesh axis
  kReduceBit,         // one global reduction over a bit-plane (OR tree / count) to the host
  kBroadcastBit,      // the controller broadcasts one host bit to every PE
  kHostPlane,         // move one bit-plane (one bit of every PE) between host and array
  kCount
};
inline constexpr int kMicroOpCount = static_cast<int>(MicroOp::kCount);
const char* MicroOpName(MicroOp op);  // "readInternal", ... (the profile's entry names)

// The cycle classes of the report.
enum class CycleClass : int {
  kAlu,
  kInternalMemory,
  kExternalMemory,
  kCommunication,
  kReduction,
  kHost,
  kCount
};
inline constexpr int kCycleClassCount = static_cast<int>(CycleClass::kCount);
const char* CycleClassName(CycleClass c);  // "alu", "internalMemory", ...
CycleClass ClassOf(MicroOp op);

// A mesh shape: extents along each axis, x fastest (PE index = x + X*(y + Y*z)).
struct MeshShape {
  std::vector<int> extent;  // {64,128}, {16,32,16}, {128,128}
  int Size() const;
  std::string Name() const;  // "64x128"
};

struct MachineProfile;

// Micro-op counts of a schedule (bitserial/cost.h), per layer; priced by a profile.
struct MicroOpCounts {
  std::array<int64_t, kMicroOpCount> n{};
  void Add(MicroOp op, int64_t k = 1) { n[static_cast<int>(op)] += k; }
  int64_t operator[](MicroOp op) const { return n[static_cast<int>(op)]; }
  MicroOpCounts& operator+=(const MicroOpCounts& o) {
    for (int i = 0; i < kMicroOpCount; ++i) n[i] += o.n[i];
    return *this;
  }
  double Cycles(const MachineProfile& p) const;
  std::array<double, kCycleClassCount> ByClass(const MachineProfile& p) const;
};

struct MachineProfile {
  std::string name;
  std::string source;   // where the numbers come from
  double clockHz = 0;   // cycles per second
  int physicalPes = 0;  // PEs in the array
  int64_t internalBitsPerPe = 0;
  int64_t externalBitsPerPe = 0;
  std::vector<MeshShape> shapes;  // the shapes software may choose; [0] is the default
  // Whether the machine's native floating point keeps IEEE gradual underflow
  // (subnormals) or flushes to zero: the default float format of `zephyr cycles --bits`
  // (bitserial/float.h). Table entry "floatSubnormals" (1 or 0) with its note.
  bool floatSubnormals = true;
  std::string floatNote;
  std::array<double, kMicroOpCount> cost{};       // cycles per micro-op
  std::array<std::string, kMicroOpCount> note{};  // "Batcher 1980 ..." or "assumed: ..."

  double Cost(MicroOp op) const { return cost[static_cast<int>(op)]; }
  // "readExternal=3": overrides one entry; throws UserError on an unknown name or value.
  void Override(const std::string& assignment);
  // The profile's table as readable text (one row per micro-op with its note).
  std::string Table() const;
};

// Builds a named profile from its table ("wavetracer", "mpp"); throws UserError for an
// unknown name (listing the known ones) or a table that lacks an entry (naming it).
MachineProfile Profile(const std::string& name);
std::vector<std::string> ProfileNames();

// The check behind Profile(): every micro-op must have an entry. Exposed for the tests.
// `entries` maps entry names to (cost, note).
MachineProfile ProfileFromTable(
    const std::string& name, const std::map<std::string, std::pair<double, std::string>>& entries);

}  // namespace zephyr::bitserial
