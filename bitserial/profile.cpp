#include "bitserial/profile.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

#include "fixed/check.h"

namespace zephyr::bitserial {

namespace {
constexpr const char* kMicroOpNames[kMicroOpCount] = {
    "readInternal", "writeInternal",   "readExternal",     "writeExternal", "aluStep",
    "flagOp",       "accumulatorRead", "accumulatorWrite", "activitySet",   "meshHop",
    "reduceBit",    "broadcastBit",    "hostPlane"};
constexpr const char* kClassNames[kCycleClassCount] = {
    "alu", "internalMemory", "externalMemory", "communication", "reduction", "host"};

using Table = std::map<std::string, std::pair<double, std::string>>;

// ---- WaveTracer Zephyr -----------------------------------------------------------------
// Facts: paper §5.1 (8192 PEs, 64x128 or 16x32x16, ~2 Kbit internal + 32 KB external per
// PE). Nothing about its timing survives in any source we found (docs/background.md, "The
// machine"), so every cost below is an ASSUMPTION, each with the reason for its value.
Table WaveTracerTable() {
  return {
      {"clockHz",
       {10e6, "assumed: an era-typical 10 MHz, as the Goodyear MPP (docs/background.md)"}},
      {"physicalPes", {8192, "paper §5.1: two boards of 4096 one-bit PEs"}},
      {"internalBitsPerPe", {2048, "paper §5.1: about 2 Kbit of internal memory per PE"}},
      {"externalBitsPerPe", {32 * 1024 * 8, "paper §5.1: 32 KB of external memory per PE"}},
      {"readInternal", {1, "assumed: one on-chip memory access per cycle, as on the MPP"}},
      {"writeInternal", {1, "assumed: as readInternal"}},
      {"readExternal",
       {2,
        "assumed: off-chip memory behind the PE chips, taken as twice an "
        "on-chip access"}},
      {"writeExternal", {2, "assumed: as readExternal"}},
      {"aluStep",
       {1,
        "assumed: a PE does either a memory access or a logic step in a cycle "
        "(conservative; the MPP overlaps them)"}},
      {"flagOp", {1, "assumed: one cycle to clear/set/latch a PE flag, as on the MPP"}},
      {"accumulatorRead",
       {1,
        "assumed: no shift register is documented for the Zephyr, so "
        "the partial product lives in internal memory"}},
      {"accumulatorWrite", {1, "assumed: as accumulatorRead"}},
      {"activitySet", {1, "assumed: one cycle to load the activity flag, as a flagOp"}},
      {"meshHop", {1, "assumed: nearest-neighbour wires move one bit per cycle, as on the MPP"}},
      {"reduceBit",
       {13,
        "assumed: a global OR/count tree over 8192 PEs, one cycle per "
        "level, log2(8192) = 13 levels"}},
      {"broadcastBit", {1, "assumed: the controller puts a host bit on the instruction bus"}},
      {"floatSubnormals",
       {1,
        "assumed: IEEE 754 gradual underflow (the paper does not say "
        "how MultiC's multi float underflowed)"}},
      {"hostPlane",
       {2048,
        "assumed: SCSI at 5 MB/s moves one 1 KB bit-plane in 204.8 us = "
        "2048 cycles at 10 MHz"}},
  };
}

// ---- Goodyear MPP ------------------------------------------------------------------------
// Batcher, "Design of a Massively Parallel Processor", IEEE Trans. Computers C-29(9), 1980:
// 128x128 PEs, 100 ns cycle, 1024 bits of RAM per PE, one memory access per cycle with the
// full adder and the shift register working in the same cycle. With these costs the
// engine's add and multiply schedules give 3n+1 and n^2+3n cycles (8-bit: 25 and 88), the
// published 6553 and 1861 MOPS.
Table MppTable() {
  return {
      {"clockHz", {10e6, "Batcher 1980: 100 ns cycle"}},
      {"physicalPes", {16384, "Batcher 1980: 128x128 array"}},
      {"internalBitsPerPe", {1024, "Batcher 1980: 1024 bits of RAM per PE"}},
      {"externalBitsPerPe", {0, "Batcher 1980: no per-PE memory beyond the 1024-bit RAM"}},
      {"readInternal", {1, "Batcher 1980: one RAM access per 100 ns cycle"}},
      {"writeInternal", {1, "Batcher 1980: one RAM access per 100 ns cycle"}},
      {"readExternal", {1, "unused: the MPP has no external PE memory (capacity 0)"}},
      {"writeExternal", {1, "unused: the MPP has no external PE memory (capacity 0)"}},
      {"aluStep", {0, "Batcher 1980: the full adder works in the cycle of the memory access"}},
      {"flagOp", {1, "Batcher 1980: clearing/loading the C or G register takes a cycle"}},
      {"accumulatorRead",
       {0,
        "Batcher 1980: the partial product circulates in the PE's "
        "shift register, in the same cycle"}},
      {"accumulatorWrite", {0, "Batcher 1980: as accumulatorRead"}},
      {"activitySet", {1, "Batcher 1980: loading the G (mask) register takes a cycle"}},
      {"meshHop", {1, "Batcher 1980: a bit-plane moves one PE per cycle on the mesh"}},
      {"reduceBit", {1, "assumed: the sum-OR tree is pipelined, one plane per cycle"}},
      {"broadcastBit", {1, "assumed: one cycle on the control unit's broadcast path"}},
      {"floatSubnormals",
       {0,
        "assumed: the MPP (1980) predates IEEE 754 (1985) and its "
        "gradual underflow; machines of its time flushed to zero"}},
      {"hostPlane",
       {128,
        "Batcher 1980: planes enter and leave through the 128-bit-wide S "
        "register columns, 128 bits per cycle"}},
  };
}

const std::map<std::string, Table (*)()>& Registry() {
  static const std::map<std::string, Table (*)()> registry = {{"mpp", &MppTable},
                                                              {"wavetracer", &WaveTracerTable}};
  return registry;
}

double ParseNumber(const std::string& text, const std::string& what) {
  char* end = nullptr;
  double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !(v >= 0) || !std::isfinite(v))
    throw UserError(fmt::format("{}: expected a finite non-negative number, got '{}'", what, text));
  return v;
}
}  // namespace

const char* MicroOpName(MicroOp op) { return kMicroOpNames[static_cast<int>(op)]; }
const char* CycleClassName(CycleClass c) { return kClassNames[static_cast<int>(c)]; }

CycleClass ClassOf(MicroOp op) {
  switch (op) {
    case MicroOp::kReadInternal:
    case MicroOp::kWriteInternal:
    case MicroOp::kAccumulatorRead:
    case MicroOp::kAccumulatorWrite:
      return CycleClass::kInternalMemory;
    case MicroOp::kReadExternal:
    case MicroOp::kWriteExternal:
      return CycleClass::kExternalMemory;
    case MicroOp::kMeshHop:
      return CycleClass::kCommunication;
    case MicroOp::kReduceBit:
      return CycleClass::kReduction;
    case MicroOp::kHostPlane:
      return CycleClass::kHost;
    default:
      return CycleClass::kAlu;
  }
}

int MeshShape::Size() const {
  int n = 1;
  for (int e : extent) n *= e;
  return n;
}

std::string MeshShape::Name() const {
  std::string s;
  for (size_t i = 0; i < extent.size(); ++i) s += (i ? "x" : "") + std::to_string(extent[i]);
  return s;
}

MachineProfile ProfileFromTable(const std::string& name, const Table& entries) {
  MachineProfile p;
  p.name = name;
  auto take = [&](const std::string& key, std::string* note) {
    auto it = entries.find(key);
    if (it == entries.end())
      throw UserError(fmt::format("machine profile '{}' lacks the entry '{}'", name, key));
    if (note) *note = it->second.second;
    return it->second.first;
  };
  p.clockHz = take("clockHz", nullptr);
  p.physicalPes = static_cast<int>(take("physicalPes", nullptr));
  p.internalBitsPerPe = static_cast<int64_t>(take("internalBitsPerPe", nullptr));
  p.externalBitsPerPe = static_cast<int64_t>(take("externalBitsPerPe", nullptr));
  for (int i = 0; i < kMicroOpCount; ++i) p.cost[i] = take(kMicroOpNames[i], &p.note[i]);
  p.floatSubnormals = take("floatSubnormals", &p.floatNote) != 0;
  for (auto& [key, value] : entries) {
    bool known = key == "clockHz" || key == "physicalPes" || key == "internalBitsPerPe" ||
                 key == "externalBitsPerPe" || key == "floatSubnormals";
    for (int i = 0; i < kMicroOpCount; ++i) known |= key == kMicroOpNames[i];
    if (!known)
      throw UserError(fmt::format("machine profile '{}' has an unknown entry '{}'", name, key));
  }
  // The kernels load whole, aligned vectors of the widest target (8 words of 64 PEs on
  // AVX-512), so a layer is a whole number of them (docs/bitserial.md; another multiple of 64
  // crashed the AVX2 and AVX-512 kernels on the first add).
  if (p.physicalPes <= 0 || p.physicalPes % 512 != 0)
    throw UserError(
        fmt::format("machine profile '{}': physicalPes must be a positive "
                    "multiple of 512, got {}",
                    name, p.physicalPes));
  if (p.clockHz <= 0)
    throw UserError(fmt::format("machine profile '{}': clockHz must be > 0", name));
  if (name == "mpp")
    p.shapes = {MeshShape{{128, 128}}};
  else if (p.physicalPes == 8192)
    p.shapes = {MeshShape{{64, 128}}, MeshShape{{16, 32, 16}}};
  else
    p.shapes = {MeshShape{{64, p.physicalPes / 64}}};
  p.source = name == "mpp" ? "Batcher, Design of a Massively Parallel Processor, IEEE Trans. "
                             "Computers C-29(9), 1980"
                           : "paper §5.1 for the geometry; costs assumed (docs/background.md)";
  return p;
}

MachineProfile Profile(const std::string& name) {
  auto it = Registry().find(name);
  if (it == Registry().end()) {
    std::string known;
    for (auto& [n, f] : Registry()) known += (known.empty() ? "" : ", ") + n;
    throw UserError(fmt::format("unknown machine profile '{}' (known: {})", name, known));
  }
  return ProfileFromTable(name, it->second());
}

std::vector<std::string> ProfileNames() {
  std::vector<std::string> names;
  for (auto& [n, f] : Registry()) names.push_back(n);
  return names;
}

void MachineProfile::Override(const std::string& assignment) {
  auto eq = assignment.find('=');
  if (eq == std::string::npos)
    throw UserError(fmt::format("profile override '{}': expected name=value", assignment));
  std::string key = assignment.substr(0, eq);
  double v = ParseNumber(assignment.substr(eq + 1), "profile override '" + assignment + "'");
  if (key == "clockHz") {
    if (!(v > 0))
      throw UserError(
          fmt::format("profile override '{}': expected a clock above 0 Hz", assignment));
    clockHz = v;
    return;
  }
  if (key == "internalBitsPerPe" || key == "externalBitsPerPe") {
    // A whole number of bits, at most 2^40 per PE (far beyond any machine; the cast to
    // int64_t stays defined).
    if (v != std::floor(v) || v > 0x1p40)
      throw UserError(fmt::format(
          "profile override '{}': expected a whole number of bits from 0 to 2^40", assignment));
    (key == "internalBitsPerPe" ? internalBitsPerPe : externalBitsPerPe) = static_cast<int64_t>(v);
    return;
  }
  if (key == "floatSubnormals") {
    floatSubnormals = v != 0;
    floatNote = "overridden at run time";
    return;
  }
  for (int i = 0; i < kMicroOpCount; ++i)
    if (key == kMicroOpNames[i]) {
      cost[i] = v;
      note[i] = "overridden at run time";
      return;
    }
  throw UserError(
      fmt::format("profile override '{}': unknown entry '{}' (micro-ops: "
                  "readInternal ... hostPlane; or clockHz, internalBitsPerPe, "
                  "externalBitsPerPe, floatSubnormals)",
                  assignment, key));
}

std::string MachineProfile::Table() const {
  std::string s = fmt::format(
      "profile {} — {}\n  clock {:g} Hz, {} PEs, internal {} bits/PE, "
      "external {} bits/PE\n",
      name, source, clockHz, physicalPes, internalBitsPerPe, externalBitsPerPe);
  for (int i = 0; i < kMicroOpCount; ++i)
    s += fmt::format("  {:<17} {:>6g}  {}\n", kMicroOpNames[i], cost[i], note[i]);
  s += fmt::format("  {:<17} {:>6d}  {}\n", "floatSubnormals", floatSubnormals ? 1 : 0, floatNote);
  return s;
}

double MicroOpCounts::Cycles(const MachineProfile& p) const {
  double total = 0;
  for (int i = 0; i < kMicroOpCount; ++i) total += n[i] * p.cost[i];
  return total;
}

std::array<double, kCycleClassCount> MicroOpCounts::ByClass(const MachineProfile& p) const {
  std::array<double, kCycleClassCount> r{};
  for (int i = 0; i < kMicroOpCount; ++i)
    r[static_cast<int>(ClassOf(static_cast<MicroOp>(i)))] += n[i] * p.cost[i];
  return r;
}

}  // namespace zephyr::bitserial
