// bitserial/profile.h — machine profiles: the geometry and the cycle cost of every micro-op.
//
// Machine timing is data, not code (as a memory simulator keeps its DRAM presets): a profile is a
// file of micro-op costs plus the machine's geometry and clock, every entry with its value, unit
// and source ("assumed: ..." where no source gives one). The built-in profiles are the files
// bitserial/profiles/NAME.json, assembled into the binary so it runs from any directory; a user's
// file of the same form is read by path (docs/bitserial.md, "Machine profiles"). The engine never
// special-cases a machine; the MPP's published figures (Batcher 1980) fall out of the same
// schedules as the WaveTracer's, with different numbers in the file (docs/validation.md). Any
// numeric entry can be overridden at run time ("name=value").
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
  std::string name;         // "wavetracer", "mpp", "blitzen", or a user file's own name
  std::string description;  // one line: what machine this is
  std::string source;       // where the numbers come from
  std::string
      file;  // the file it was read from ("built-in bitserial/profiles/NAME.json" or a path)
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
  // The sources of the geometry entries (clockHz, physicalPes, internalBitsPerPe,
  // externalBitsPerPe, meshShapes), in that order.
  std::array<std::string, 5> geometryNote{};
  std::array<double, kMicroOpCount> cost{};       // cycles per micro-op
  std::array<std::string, kMicroOpCount> note{};  // "Batcher 1980 ..." or "assumed: ..."

  double Cost(MicroOp op) const { return cost[static_cast<int>(op)]; }
  // "readExternal=3": overrides one numeric entry (its source becomes "overridden at run
  // time"); throws UserError on an unknown name or a value out of the entry's range.
  void Override(const std::string& assignment);
  // The profile's table as readable text (one row per micro-op with its note).
  std::string Table() const;
  // The profile as a profile file (the layout of bitserial/profiles/*.json, one entry per
  // line): what `zephyr profile show` prints, and what ProfileFromJson reads back.
  std::string FileText() const;
};

// The profile named by a built-in name ("wavetracer", "mpp", "blitzen") or, for anything else,
// read from that path (docs/bitserial.md). Throws UserError for an unknown name that is no
// readable file (listing the built-in ones), or for a malformed file (ProfileFromJson).
MachineProfile Profile(const std::string& nameOrFile);
std::vector<std::string> ProfileNames();  // the built-in profiles, sorted
// The text of a built-in profile's file (bitserial/profiles/NAME.json as built in); throws
// UserError for an unknown name.
const std::string& BuiltInProfileText(const std::string& name);

// The largest profile file read (a built-in one has ~4 KiB) and the deepest nesting of its
// objects and lists (a profile nests three deep); past either, a UserError before parsing.
inline constexpr size_t kMaxProfileBytes = size_t(1) << 20;
inline constexpr int kMaxProfileNesting = 16;

// Reads a profile file's text (a leading UTF-8 byte-order mark is skipped). `file` names it in
// errors, which are UserErrors of the form
// "FILE:LINE:COLUMN: PATH: what is wrong" for invalid JSON, an unknown or missing key, a value
// of the wrong type, unit or range (PATH as "entries.readInternal.value").
MachineProfile ProfileFromJson(const std::string& text, const std::string& file);

}  // namespace zephyr::bitserial
