// tools/pimeval/pimeval.cpp — PIMeval's host API (libpimeval.h) on the emulated array: a client
// of the installed engine API (bitserial/multi.h, bitserial/float.h), as tools/kernels/ is.
// docs/pim.md says what is supported and the decisions; the PIMeval semantics followed are
// those of its source at github.com/UVA-LavaLab/PIMeval-PIMbench 40ce162
// (libpimeval/src/pimCmd.h, pimCmd.cpp, pimSim.cpp).
//
// Objects: each pimAlloc opens a group (its associated objects share it): one engine Machine of
// exactly the group's elements as virtual PEs, each object a Multi on it (format s(b-1).0 or
// ub.0, wrap-around) or, for PIM_FP32, a MultiFloat (IEEE binary32). On the BitSIMD-V devices
// the machine's physical PEs are the columns the group occupies (rounded up to 512), at most the
// device's ranks x banks x subarrays x columns, so a 2,048-element vector costs 2,048 PEs of
// host work while the modelled time is the device's: every column works at once, and more
// elements than columns run as layers, each with rows/layers bits of memory (PIMeval's regions
// per core).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "fixed/check.h"
#include "tools/pimeval/config.h"
#include "tools/pimeval/libpimeval.h"

namespace zephyr::pimeval {
namespace {

using bitserial::LogicOp;
using bitserial::Machine;
using bitserial::MachineProfile;
using bitserial::MicroOp;
using bitserial::MicroOpCounts;
using bitserial::Multi;
using bitserial::MultiFloat;
using bitserial::UniFloat;
using bitserial::Uni;
using bitserial::WhereScope;
using bitserial::Word;
using fixed::BigInt;
using fixed::Format;

// ---- types ------------------------------------------------------------------------------------
struct TypeInfo {
  int bits = 0;        // bits per element on the array
  bool isSigned = false;
  int bytes = 0;       // bytes per element on the host
  const char* name = "";
  bool isFloat = false;  // PIM_FP32: IEEE binary32, its bit pattern held as ub.0 (Fmt())
  // The format of the element's bits on the array (for a float, its bit pattern's).
  Format Fmt() const { return isSigned ? Format::Signed(bits - 1, 0) : Format::Unsigned(bits, 0); }
};

// PIM_FP32's format on the array: IEEE binary32 with subnormals, round to nearest even.
const fixed::FloatFormat kFp32 = fixed::FloatFormat::Binary32();

const char* TypeName(PimDataType t) {
  static const char* names[] = {"PIM_BOOL",   "PIM_INT8",   "PIM_INT16",  "PIM_INT32", "PIM_INT64",
                                "PIM_UINT8",  "PIM_UINT16", "PIM_UINT32", "PIM_UINT64",
                                "PIM_FP32",   "PIM_FP16",   "PIM_BF16",   "PIM_FP8"};
  return t >= 0 && t <= PIM_FP8 ? names[t] : "an unknown PimDataType";
}

TypeInfo Info(PimDataType t) {
  switch (t) {
    case PIM_BOOL: return {1, false, 1, "BOOL"};
    case PIM_INT8: return {8, true, 1, "INT8"};
    case PIM_INT16: return {16, true, 2, "INT16"};
    case PIM_INT32: return {32, true, 4, "INT32"};
    case PIM_INT64: return {64, true, 8, "INT64"};
    case PIM_UINT8: return {8, false, 1, "UINT8"};
    case PIM_UINT16: return {16, false, 2, "UINT16"};
    case PIM_UINT32: return {32, false, 4, "UINT32"};
    case PIM_UINT64: return {64, false, 8, "UINT64"};
    case PIM_FP32: return {32, false, 4, "FP32", true};
    default:
      throw UserError(fmt::format(
          "data type {} ({}) is not supported: this library emulates PIM_BOOL, PIM_INT8..64, "
          "PIM_UINT8..64 and PIM_FP32 (PIMeval keeps FP16, BF16 and FP8 as 4-byte floats computed "
          "in FP32 and charges the narrower width's time; an array computing in the narrow format "
          "would round differently, one computing in FP32 would not cost the narrow time; "
          "docs/pim.md)",
          TypeName(t), int(t)));
  }
}

const char* DeviceName(PimDeviceEnum d) {
  static const char* names[] = {"PIM_DEVICE_NONE",         "PIM_FUNCTIONAL",
                                "PIM_DEVICE_BITSIMD_V",    "PIM_DEVICE_BITSIMD_V_NAND",
                                "PIM_DEVICE_BITSIMD_V_MAJ", "PIM_DEVICE_BITSIMD_V_AP",
                                "PIM_DEVICE_DRISA_NOR",    "PIM_DEVICE_DRISA_MIXED",
                                "PIM_DEVICE_SIMDRAM",      "PIM_DEVICE_BITSIMD_H",
                                "PIM_DEVICE_FULCRUM",      "PIM_DEVICE_BANK_LEVEL",
                                "PIM_DEVICE_AQUABOLT",     "PIM_DEVICE_AIM"};
  return d >= 0 && d <= PIM_DEVICE_AIM ? names[d] : "an unknown PimDeviceEnum";
}

std::optional<PimDeviceEnum> DeviceFromName(const std::string& s) {
  for (int d = 0; d <= PIM_DEVICE_AIM; ++d)
    if (s == DeviceName(PimDeviceEnum(d))) return PimDeviceEnum(d);
  return std::nullopt;
}

// The simulation target a device runs as, or UserError naming what it would need.
PimDeviceEnum CheckTarget(PimDeviceEnum d) {
  switch (d) {
    case PIM_FUNCTIONAL:
    case PIM_DEVICE_BITSIMD_V: return PIM_DEVICE_BITSIMD_V;
    case PIM_DEVICE_BITSIMD_V_AP: return PIM_DEVICE_BITSIMD_V_AP;
    case PIM_DEVICE_BITSIMD_V_NAND:
    case PIM_DEVICE_BITSIMD_V_MAJ:
    case PIM_DEVICE_DRISA_NOR:
    case PIM_DEVICE_DRISA_MIXED:
    case PIM_DEVICE_SIMDRAM:
      throw UserError(fmt::format(
          "device {} is a bit-serial design whose micro-op costs differ from BitSIMD-V's; it would "
          "need a machine profile of its costs (ZEPHYR_MACHINE=FILE runs any profile)",
          DeviceName(d)));
    case PIM_DEVICE_BITSIMD_H:
    case PIM_DEVICE_FULCRUM:
    case PIM_DEVICE_BANK_LEVEL:
    case PIM_DEVICE_AQUABOLT:
    case PIM_DEVICE_AIM:
      throw UserError(fmt::format(
          "device {} is bit-parallel (horizontal layout, word-wide ALUs per subarray or bank); "
          "this library emulates bit-serial vertical-layout arrays only: it would need a "
          "word-parallel engine (use PIM_FUNCTIONAL, PIM_DEVICE_BITSIMD_V or _V_AP)",
          DeviceName(d)));
    default:
      throw UserError(fmt::format("device type {} ({}) is not a device", DeviceName(d), int(d)));
  }
}

// ---- state ------------------------------------------------------------------------------------
// The objects of one pimAlloc and those associated with it: one machine.
struct Group {
  int id = 0;
  uint64_t elements = 0;
  // Elements per PIMeval region (one core's share in one pass): the subarray's columns, divided
  // by the bits per element in the horizontal layout; on a ZEPHYR_MACHINE profile, its PEs.
  uint64_t regionElements = 0;
  std::unique_ptr<Machine> machine;
  int live = 0;
  std::optional<bitserial::CycleReport> finalReport;  // kept when the last object is freed
  const bitserial::CycleReport& Report() const {
    return machine ? machine->Report() : *finalReport;
  }
};

struct Object {
  PimDataType type;
  TypeInfo info;
  std::shared_ptr<Group> group;
  Multi value;         // an integer or BOOL object's elements (empty for PIM_FP32)
  MultiFloat fvalue;   // a PIM_FP32 object's elements (empty otherwise)
  // The elements' bits, whatever the type (copies, conditionals, moves, bit slices).
  Multi& Raw() { return info.isFloat ? fvalue.Bits() : value; }
  const Multi& Raw() const { return info.isFloat ? fvalue.Bits() : value; }
};

struct Device {
  PimDeviceEnum type = PIM_DEVICE_NONE, target = PIM_DEVICE_NONE;
  Geometry geometry;
  MachineProfile profile;  // the device's profile (physicalPes set per group)
  bool custom = false;     // ZEPHYR_MACHINE: the profile as it is
  std::string memoryFile;
  std::map<PimObjId, std::unique_ptr<Object>> objects;
  PimObjId nextId = 0;
};

struct OpStat {
  int64_t calls = 0;
  double seconds = 0;
};
struct Stats {
  std::map<std::string, OpStat> ops;  // by "pimAdd INT32"
  uint64_t bytesToDevice = 0, bytesToHost = 0;
  double secondsToDevice = 0, secondsToHost = 0;
  std::vector<std::shared_ptr<Group>> groups;  // every group of the device, for the report
  double timerSeconds = 0;
  std::optional<std::chrono::steady_clock::time_point> timerStart;
};

std::unique_ptr<Device> g_device;
Stats g_stats;

double ModelledSeconds() {
  double s = 0;
  for (const auto& g : g_stats.groups) s += g->Report().ModelledSeconds();
  return s;
}

Device& Dev() {
  if (!g_device) throw UserError("no device: call pimCreateDevice or pimCreateDeviceFromConfig first");
  return *g_device;
}

Object& Obj(PimObjId id) {
  Device& d = Dev();
  auto it = d.objects.find(id);
  if (it == d.objects.end()) throw UserError(fmt::format("object id {} does not exist", id));
  return *it->second;
}

// Runs one API call: its errors become PIM_ERROR with a message, its modelled time goes to the
// table under the key `body` returns.
template <typename F>
PimStatus Call(const char* api, F&& body) {
  try {
    const double t0 = g_device ? ModelledSeconds() : 0;
    std::string key = body();
    OpStat& s = g_stats.ops[key.empty() ? std::string(api) : std::string(api) + " " + key];
    s.calls += 1;
    s.seconds += ModelledSeconds() - t0;
    return PIM_OK;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "PIM-Error: %s: %s\n", api, e.what());
    return PIM_ERROR;
  }
}

PimStatus Refuse(const char* api, const std::string& why) {
  std::fprintf(stderr, "PIM-Error: %s: %s\n", api, why.c_str());
  return PIM_ERROR;
}

// ---- the machine of a group ---------------------------------------------------------------
// The profile of a group of n elements. `rowBits` is how many columns one element takes in a
// row: 1 in the vertical layout; the first object's bits per element in the horizontal one
// (PIM_ALLOC_H/H1), whose elements PIMeval's BitSIMD model charges as the vertical layout's
// operations over as many passes as the horizontal regions take per core — so the device
// counts as Pes / rowBits columns of rows x rowBits bits each (at least 512, the engine's
// vector), the elements computed bit-serially as ever.
MachineProfile GroupProfile(const Device& d, uint64_t n, int rowBits) {
  MachineProfile p = d.profile;
  if (d.custom) return p;
  // The engine's planes are whole vectors of 512 PEs (a profile's physicalPes is a multiple
  // of 512, bitserial/profile.cpp): the columns used are rounded up to one.
  const uint64_t columns = std::max<uint64_t>(512, d.geometry.Pes() / rowBits / 512 * 512);
  const uint64_t pes = std::min((n + 511) / 512 * 512, columns);
  if (pes > (uint64_t{1} << 30))
    throw UserError(fmt::format("{} elements: more than 2^30 PEs in one layer are not emulated", n));
  const double bytesPerSecond =
      d.profile.physicalPes / 8.0 / d.profile.Cost(MicroOp::kHostPlane) * d.profile.clockHz;
  p.physicalPes = static_cast<int>(pes);
  p.shapes = {bitserial::MeshShape{{static_cast<int>(pes)}}};
  p.internalBitsPerPe = d.geometry.rows * rowBits;
  p.externalBitsPerPe = 0;
  p.geometryNote[1] = fmt::format(
      "the {} columns this group's {} elements occupy (of the device's {} = {} ranks x {} banks "
      "x {} subarrays x {} columns{}), rounded up to 512; more elements than columns run as layers",
      pes, n, d.geometry.Pes(), d.geometry.ranks, d.geometry.banks, d.geometry.subarrays,
      d.geometry.cols,
      rowBits == 1 ? "" : fmt::format("; horizontal layout: {} columns per element", rowBits));
  p.geometryNote[2] = rowBits == 1
                          ? fmt::format("the device's {} rows per subarray", d.geometry.rows)
                          : fmt::format("the device's {} rows per subarray x the {} columns of "
                                        "a horizontal element",
                                        d.geometry.rows, rowBits);
  p.geometryNote[3] = "one space: the rows are internal memory";
  p.geometryNote[4] = "one chain of the group's columns";
  p.cost[int(MicroOp::kHostPlane)] =
      pes / 8.0 / (bytesPerSecond * d.geometry.ranks) * d.profile.clockHz;
  p.note[int(MicroOp::kHostPlane)] = fmt::format(
      "a plane of {} bits over {} rank(s) at the profile's {:.4g} GB/s per rank (PIMeval: bytes / "
      "(rank bandwidth x ranks), pimPerfEnergyBase.cpp:90)",
      pes, d.geometry.ranks, bytesPerSecond / 1e9);
  return p;
}

Object& NewObject(Device& d, PimDataType type, std::shared_ptr<Group> g, PimObjId* id) {
  const TypeInfo info = Info(type);
  auto o = std::make_unique<Object>(Object{type, info, g, Multi(), MultiFloat()});
  try {
    if (info.isFloat)
      o->fvalue = MultiFloat(*g->machine, kFp32, fmt::format("obj{}", d.nextId));
    else
      o->value = Multi(*g->machine, info.Fmt(), fmt::format("obj{}", d.nextId));
  } catch (const UserError& e) {
    throw UserError(fmt::format(
        "{} elements of {} ({} bits each) do not fit: the device's columns hold {} rows, {} "
        "element(s) per column ({} layer(s)); {}",
        g->elements, TypeName(type), info.bits, d.geometry.rows,
        g->machine->ModelledLayers(), g->machine->ModelledLayers(), e.what()));
  }
  g->live += 1;
  *id = d.nextId++;
  Object& ref = *o;
  d.objects[*id] = std::move(o);
  return ref;
}

// ---- helpers on the array -------------------------------------------------------------------
BigInt Mask(int bits) { return (BigInt(1) << bits) - 1; }
// v modulo 2^bits, in [0, 2^bits): the low bits of v's two's-complement pattern.
uint64_t LowBits(const BigInt& v, int bits) {
  const BigInt m = BigInt(1) << bits;
  BigInt r = v % m;
  if (r < 0) r += m;
  return r.convert_to<uint64_t>();
}

// The scalar's low `bits` as a value of the element's format (C++'s wrap to the type).
fixed::Fixed Wrapped(const TypeInfo& t, uint64_t scalar) {
  return fixed::Fixed::FromBits(t.Fmt(), BigInt(scalar) & Mask(t.bits));
}
// The scalar as PIMeval widens it (int64_t for signed types, uint64_t for unsigned), in the
// element's format when it fits there, else in a 64-bit one.
fixed::Fixed Exact(const TypeInfo& t, uint64_t scalar) {
  const BigInt v = t.isSigned ? BigInt(static_cast<int64_t>(scalar)) : BigInt(scalar);
  const Format f = t.Fmt();
  if (v >= f.MinRaw() && v <= f.MaxRaw()) return {f, v};
  return {t.isSigned ? Format::Signed(63, 0) : Format::Unsigned(64, 0), v};
}

// A 1-bit multi, 1 at the elements [b, e): loaded from the host (one plane, charged).
Multi RangeMask(Group& g, uint64_t b, uint64_t e) {
  Multi m(*g.machine, bitserial::BoolFormat(), "range");
  std::vector<int64_t> raw(e, 0);
  for (uint64_t i = b; i < e; ++i) raw[i] = 1;
  m.LoadRaw(raw);
  return m;
}

// Element i of a multi read to the host: a reduction under a one-element mask (charged).
fixed::Fixed ReadElement(Group& g, const Multi& a, uint64_t i) {
  const Multi one = RangeMask(g, i, i + 1);
  WhereScope w(one);
  return ReduceOr(a);
}

// Bitwise op over every bit-plane of a (and b's or the uni's), with the engine's 1-bit logic
// kernel and charge per plane; `invert` complements the result (one more ALU step per plane).
Multi Bitwise(const char* name, LogicOp op, const Multi& a, const Multi* b,
              const fixed::Fixed* uni, bool invert, Format out) {
  Machine& m = a.GetMachine();
  Multi r(m, out, name, Multi::Uninitialised{});
  const size_t words = m.WordsPerPlane();
  MicroOpCounts counts;
  const bitserial::Operand bit{bitserial::BoolFormat(), a.GetSpace(), false};
  for (int i = 0; i < out.Width(); ++i) {
    const Word* pb = b ? b->Plane(i) : uni ? (uni->Bit(i) ? m.OnesPlane() : m.ZeroPlane()) : nullptr;
    m.Kernels().logic(op, a.Plane(i), pb, r.Plane(i), words);
    if (invert) m.Kernels().logic(LogicOp::kNot, r.Plane(i), nullptr, r.Plane(i), words);
    counts += bitserial::LogicCost(bit, b != nullptr, r.GetSpace());
    if (invert) counts.Add(MicroOp::kAluStep);
  }
  m.Charge(name, counts);
  return r;
}

// Bit i of every element as a 1-bit multi: one row copied (charged as a 1-bit copy).
Multi Slice(const Multi& a, int i) {
  Machine& m = a.GetMachine();
  Multi r(m, bitserial::BoolFormat(), "slice", Multi::Uninitialised{});
  m.Kernels().logic(LogicOp::kOr, a.Plane(i), m.ZeroPlane(), r.Plane(0), m.WordsPerPlane());
  m.Charge("bitSlice", bitserial::CopyCost({bitserial::BoolFormat(), a.GetSpace(), false},
                                           r.AsOperand()));
  return r;
}

void Store(Object& d, Multi r) {
  if (r.Format() != d.info.Fmt()) r = Convert(r, d.info.Fmt());
  d.Raw() = std::move(r);
}
// A float result into a PIM_FP32 object.
void Store(Object& d, MultiFloat r) { d.fvalue = std::move(r); }

// A bit-pattern multi (ub.32) as a PIM_FP32 value: its planes taken over, nothing moved or
// charged. Outside any where only (inside one the planes would be copied where active).
MultiFloat AsFloat(Multi bits) {
  MultiFloat f(bits.GetMachine(), kFp32, "fp32");
  f.Bits() = std::move(bits);
  return f;
}

// A PIMeval scalar as a PIM_FP32 operand: the uint64_t's low 32 bits are the float's pattern
// (PIMeval reads it with castBitsToType<float>, pimUtils.h).
UniFloat FloatScalar(uint64_t bits) { return {kFp32, bits & 0xffffffffu}; }
float FloatOf(uint64_t bits) {
  const uint32_t b = static_cast<uint32_t>(bits);
  float f;
  std::memcpy(&f, &b, 4);
  return f;
}
uint32_t BitsOf(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

// A call that applies to integers and BOOL only, on a PIM_FP32 object: UserError naming it
// (PIMeval refuses these on floats too: "Cannot perform bitwise operation on floating point").
void CheckNotFloat(const Object& o, PimObjId id, const char* what) {
  if (o.info.isFloat)
    throw UserError(fmt::format("object {} is PIM_FP32: {} do not apply to floating point", id, what));
}

void CheckSameGroup(const Object& a, const Object& b, PimObjId ia, PimObjId ib) {
  if (a.group != b.group)
    throw UserError(fmt::format(
        "objects {} and {} are not associated (allocate one with pimAllocAssociated of the other)",
        ia, ib));
}
void CheckType(const Object& o, PimObjId id, PimDataType t, const char* role) {
  if (o.type != t)
    throw UserError(fmt::format("{} object {} is {}, expected {}", role, id, TypeName(o.type),
                                TypeName(t)));
}

// [b, e) of an object of n elements as a range reduction sees it: e = 0 means to the end.
std::pair<uint64_t, uint64_t> ReductionRange(uint64_t n, uint64_t b, uint64_t e, PimObjId id) {
  if (b > n)
    throw UserError(fmt::format("range begin {} is past object {}'s {} elements", b, id, n));
  if (e == 0) e = n;
  if (e < b) throw UserError(fmt::format("range end {} is before its begin {}", e, b));
  return {b, std::min(e, n)};
}
// [b, e) of a copy: 0, 0 means all; otherwise both within the object.
std::pair<uint64_t, uint64_t> CopyRange(uint64_t n, uint64_t b, uint64_t e, PimObjId id) {
  if (b == 0 && e == 0) return {0, n};
  if (b > n || e > n)
    throw UserError(fmt::format("copy range [{}, {}) is outside object {}'s {} elements", b, e, id, n));
  if (e < b) throw UserError(fmt::format("copy range end {} is before its begin {}", e, b));
  return {b, e};
}

// Whether the n elements of machine m can move along their chain: one layer of a 1-D mesh, or
// whole layers (the engine's virtual mesh).
bool ElementsCanMove(const Machine& m, uint64_t n) {
  return (m.Layers() == 1 && m.Shape().extent.size() == 1) ||
         static_cast<int64_t>(n) % m.Profile().physicalPes == 0;
}

// Shifts a multi by d elements along the chain of elements: +1 moves element i to i+1.
Multi ShiftElements(const Multi& a, int d, uint64_t n) {
  Machine& m = a.GetMachine();
  if (m.Layers() == 1 && m.Shape().extent.size() == 1) return MeshShift(a, 0, d);
  const int64_t pes = m.Profile().physicalPes;
  if (!ElementsCanMove(m, n))
    throw UserError(fmt::format(
        "moving {} elements along their chain takes whole layers of the machine's {} PEs on "
        "machine '{}' ({} layer(s), mesh {}): allocate a multiple of {} elements",
        n, pes, m.Profile().name, m.Layers(), m.Shape().Name(), pes));
  return MeshShift(a, bitserial::MeshShape{{static_cast<int>(n)}}, 0, d);
}

// The signed quotient truncated toward zero, from the magnitudes (C++'s integer division).
Multi SignedQuotient(const Multi& q, const Multi& negative, Format out) {
  return Select(negative, Neg(q, out), q, out);
}

const fixed::Fixed Zero(const TypeInfo& t) { return {t.Fmt(), 0}; }

// ---- device creation ------------------------------------------------------------------------
void CreateDevice(PimDeviceEnum type, PimDeviceEnum target, Geometry g, const std::string& memFile,
                  unsigned bufferSize) {
  if (g_device) throw UserError("a device exists already: pimDeleteDevice first");
  if (bufferSize != 0)
    throw UserError(fmt::format("bufferSize {} is AiM's on-chip buffer; no bank-level device here",
                                bufferSize));
  if (g.ranks == 0 || g.banks == 0 || g.subarrays == 0 || g.rows == 0 || g.cols == 0)
    throw UserError(fmt::format("every dimension must be at least 1: {} ranks, {} banks, {} "
                                "subarrays, {} rows, {} columns",
                                g.ranks, g.banks, g.subarrays, g.rows, g.cols));
  if (g.Pes() < 512)
    throw UserError(fmt::format("{} PEs: a device needs at least 512 columns in all (the "
                                "engine's vector of PEs)", g.Pes()));
  auto d = std::make_unique<Device>();
  d->type = type;
  d->target = target;
  d->geometry = g;
  const char* env = std::getenv("ZEPHYR_MACHINE");
  if (env && *env) {
    d->profile = bitserial::Profile(env);
    d->custom = true;
  } else {
    d->profile = bitserial::Profile("pim-bitsimd-v-bank");
    const double baseColumns = 8192;  // columns per subarray of pim-bitsimd-v-bank.json
    if (!memFile.empty()) {
      ApplyMemoryTimings(d->profile, ReadMemoryIni(memFile), memFile, g.cols);
    } else {
      d->profile.cost[int(MicroOp::kReduceBit)] *= g.cols / baseColumns;
    }
    d->profile.name = fmt::format("pim-bitsimd-v {}x{}x{}x{}", g.ranks, g.banks, g.subarrays, g.cols);
  }
  d->memoryFile = memFile;
  g_stats = Stats();
  g_device = std::move(d);
}

}  // namespace
}  // namespace zephyr::pimeval

using namespace zephyr;
using namespace zephyr::pimeval;

// ---- statistics -------------------------------------------------------------------------------
void pimStartTimer() { g_stats.timerStart = std::chrono::steady_clock::now(); }
void pimEndTimer() {
  if (g_stats.timerStart)
    g_stats.timerSeconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - *g_stats.timerStart).count();
  g_stats.timerStart.reset();
}
bool pimIsAnalysisMode() { return false; }

void pimResetStats() {
  g_stats.ops.clear();
  g_stats.bytesToDevice = g_stats.bytesToHost = 0;
  g_stats.secondsToDevice = g_stats.secondsToHost = 0;
  g_stats.timerSeconds = 0;
  std::vector<std::shared_ptr<Group>> live;
  for (auto& g : g_stats.groups)
    if (g->machine) {
      g->machine->Report().Clear();
      live.push_back(g);
    }
  g_stats.groups = live;
}

void pimShowStats() {
  std::string out;
  const Device* d = g_device.get();
  out += "----------------------------------------\n";
  out += "Zephyr PIMeval API (bit-serial on the emulated array, docs/pim.md)\n";
  if (d)
    out += fmt::format(
        "Device: {} (simulation target {}), {} rank(s) x {} banks x {} subarrays x {} columns, {} "
        "rows; machine profile {}{}\n",
        DeviceName(d->type), DeviceName(d->target), d->geometry.ranks, d->geometry.banks,
        d->geometry.subarrays, d->geometry.cols, d->geometry.rows, d->profile.name,
        d->custom ? " (ZEPHYR_MACHINE)" : "");
  out += "Data copy:\n";
  out += fmt::format("  {:<28} {:>14} bytes {:>14.6f} ms\n", "host to device", g_stats.bytesToDevice,
                     g_stats.secondsToDevice * 1e3);
  out += fmt::format("  {:<28} {:>14} bytes {:>14.6f} ms\n", "device to host", g_stats.bytesToHost,
                     g_stats.secondsToHost * 1e3);
  out += fmt::format("PIM operations:\n  {:<28} {:>14} {:>20}\n", "call", "calls", "modelled ms");
  double total = 0, copies = 0;
  int64_t calls = 0;
  nlohmann::json ops = nlohmann::json::object();
  for (const auto& [name, s] : g_stats.ops) {
    out += fmt::format("  {:<28} {:>14} {:>20.6f}\n", name, s.calls, s.seconds * 1e3);
    ops[name] = {{"calls", s.calls}, {"modelledMs", s.seconds * 1e3}};
    total += s.seconds;
    calls += s.calls;
  }
  out += fmt::format("  {:<28} {:>14} {:>20.6f}\n", "total", calls, total * 1e3);
  copies = g_stats.secondsToDevice + g_stats.secondsToHost;
  out += fmt::format("Modelled time: {:.6f} ms in all, {:.6f} ms of it host<->device copies, {:.6f} ms "
                     "kernel\n",
                     total * 1e3, copies * 1e3, (total - copies) * 1e3);
  if (g_stats.timerSeconds > 0)
    out += fmt::format("Host wall time between pimStartTimer and pimEndTimer: {:.6f} ms\n",
                       g_stats.timerSeconds * 1e3);
  nlohmann::json groups = nlohmann::json::array();
  for (const auto& g : g_stats.groups) {
    const auto& r = g->Report();
    out += fmt::format("\nCycle report: objects of {} elements (group {}, {} layer(s))\n", g->elements,
                       g->id, r.Layers());
    out += r.Table();
    groups.push_back({{"group", g->id}, {"elements", g->elements}, {"report", r.Json()}});
  }
  if (!g_stats.groups.empty()) {
    out += "\nMachine profile (of the last group):\n";
    out += g_stats.groups.back()->Report().Profile().Table();
  }
  out += "----------------------------------------\n";
  std::fwrite(out.data(), 1, out.size(), stdout);
  std::fflush(stdout);
  if (const char* path = std::getenv("ZEPHYR_REPORT"); path && *path) {
    nlohmann::json j = {{"copies",
                         {{"hostToDeviceBytes", g_stats.bytesToDevice},
                          {"deviceToHostBytes", g_stats.bytesToHost},
                          {"hostToDeviceMs", g_stats.secondsToDevice * 1e3},
                          {"deviceToHostMs", g_stats.secondsToHost * 1e3}}},
                        {"calls", ops},
                        {"modelledMs", total * 1e3},
                        {"kernelMs", (total - copies) * 1e3},
                        {"groups", groups}};
    if (d)
      j["device"] = {{"type", DeviceName(d->type)},    {"simTarget", DeviceName(d->target)},
                     {"ranks", d->geometry.ranks},     {"banks", d->geometry.banks},
                     {"subarrays", d->geometry.subarrays}, {"rows", d->geometry.rows},
                     {"cols", d->geometry.cols},       {"profile", d->profile.name}};
    std::ofstream f(path);
    f << j.dump(2) << "\n";
    if (!f) std::fprintf(stderr, "PIM-Error: pimShowStats: cannot write ZEPHYR_REPORT '%s'\n", path);
  }
}

// ---- device ---------------------------------------------------------------------------------
PimStatus pimCreateDevice(PimDeviceEnum deviceType, unsigned numRanks, unsigned numBankPerRank,
                          unsigned numSubarrayPerBank, unsigned numRows, unsigned numCols,
                          unsigned bufferSize) {
  return Call("pimCreateDevice", [&] {
    const PimDeviceEnum target = CheckTarget(deviceType);
    CreateDevice(deviceType, target,
                 Geometry{numRanks, numBankPerRank, numSubarrayPerBank, numRows, numCols}, "",
                 bufferSize);
    return std::string();
  });
}

PimStatus pimCreateDeviceFromConfig(PimDeviceEnum deviceType, const char* configFileName) {
  return Call("pimCreateDeviceFromConfig", [&] {
    if (!configFileName) throw UserError("the config file name is null");
    const DeviceConfig c = ReadDeviceConfig(configFileName);
    PimDeviceEnum asked = deviceType;
    if (deviceType == PIM_FUNCTIONAL && !c.simulationTarget.empty()) {
      auto t = DeviceFromName(c.simulationTarget);
      if (!t)
        throw UserError(fmt::format("{}: simulation_target '{}' is not a PimDeviceEnum name",
                                    configFileName, c.simulationTarget));
      asked = *t;
    }
    const PimDeviceEnum target = CheckTarget(asked);
    CreateDevice(deviceType, target, c.geometry, c.memoryFile, c.bufferSize);
    return std::string();
  });
}

PimStatus pimGetDeviceProperties(PimDeviceProperties* p) {
  return Call("pimGetDeviceProperties", [&] {
    const Device& d = Dev();
    if (!p) throw UserError("deviceProperties is null");
    p->deviceType = d.type;
    p->simTarget = d.target;
    p->numRanks = d.geometry.ranks;
    p->numBankPerRank = d.geometry.banks;
    p->numSubarrayPerBank = d.geometry.subarrays;
    p->numRowPerSubarray = d.geometry.rows;
    p->numColPerSubarray = d.geometry.cols;
    p->numPIMCores = static_cast<unsigned>(d.geometry.Cores());
    p->isHLayoutDevice = false;
    return std::string();
  });
}

PimStatus pimDeleteDevice() {
  return Call("pimDeleteDevice", [&] {
    Device& d = Dev();
    for (auto& [id, o] : d.objects) {
      { Multi dead(std::move(o->Raw())); }
      if (--o->group->live == 0) {
        o->group->finalReport = o->group->machine->Report();
        o->group->machine.reset();
      }
    }
    g_device.reset();
    return std::string();
  });
}

// ---- objects ----------------------------------------------------------------------------------
PimObjId pimAlloc(PimAllocEnum allocType, uint64_t numElements, PimDataType dataType) {
  PimObjId id = -1;
  Call("pimAlloc", [&] {
    Device& d = Dev();
    if (allocType != PIM_ALLOC_AUTO && allocType != PIM_ALLOC_V && allocType != PIM_ALLOC_V1 &&
        allocType != PIM_ALLOC_H && allocType != PIM_ALLOC_H1)
      throw UserError(fmt::format("allocation type {} is not a PimAllocEnum", int(allocType)));
    if (numElements == 0) throw UserError("an object needs at least one element");
    if (numElements > (uint64_t{1} << 31))
      throw UserError(fmt::format("{} elements: at most 2^31 are emulated", numElements));
    // The horizontal layouts: each element across bits columns of one row (docs/pim.md).
    const bool horizontal = allocType == PIM_ALLOC_H || allocType == PIM_ALLOC_H1;
    const int rowBits = horizontal ? Info(dataType).bits : 1;
    if ((allocType == PIM_ALLOC_V1 || allocType == PIM_ALLOC_H1) && !d.custom &&
        numElements * rowBits > d.geometry.Pes())
      throw UserError(fmt::format("{}: {} elements x {} column(s) exceed the device's {} columns "
                                  "(one region per core)",
                                  allocType == PIM_ALLOC_V1 ? "PIM_ALLOC_V1" : "PIM_ALLOC_H1",
                                  numElements, rowBits, d.geometry.Pes()));
    const uint64_t capacity = d.geometry.Pes() * d.geometry.rows;
    if (!d.custom && numElements * Info(dataType).bits > capacity)
      throw UserError(fmt::format("{} elements of {} need {} bits; the device holds {} ({} columns "
                                  "x {} rows)",
                                  numElements, TypeName(dataType), numElements * Info(dataType).bits,
                                  capacity, d.geometry.Pes(), d.geometry.rows));
    auto g = std::make_shared<Group>();
    g->id = static_cast<int>(g_stats.groups.size()) + 1;
    g->elements = numElements;
    g->machine =
        std::make_unique<Machine>(GroupProfile(d, numElements, rowBits), int64_t(numElements));
    g->regionElements = d.custom ? uint64_t(g->machine->Profile().physicalPes)
                                 : std::max<uint64_t>(1, d.geometry.cols / rowBits);
    g_stats.groups.push_back(g);
    NewObject(d, dataType, g, &id);
    return std::string(TypeName(dataType));
  });
  return id;
}

PimObjId pimAllocAssociated(PimObjId assocId, PimDataType dataType) {
  PimObjId id = -1;
  Call("pimAllocAssociated", [&] {
    Device& d = Dev();
    Object& ref = Obj(assocId);
    NewObject(d, dataType, ref.group, &id);
    return std::string(TypeName(dataType));
  });
  return id;
}

// PIMeval allocates the global buffer on PIM_DEVICE_AIM only ("Device does not support On-Chip
// Buffer" on every other target, pimDevice.cpp); AiM is bit-parallel and not emulated here.
PimObjId pimAllocBuffer(uint32_t, PimDataType) {
  Refuse("pimAllocBuffer",
         "the global buffer exists on PIM_DEVICE_AIM only (PIMeval refuses it on every other "
         "simulation target: \"Device does not support On-Chip Buffer\"); AiM is bit-parallel, "
         "not emulated here");
  return -1;
}

PimStatus pimFree(PimObjId obj) {
  return Call("pimFree", [&] {
    Device& d = Dev();
    Object& o = Obj(obj);
    std::shared_ptr<Group> g = o.group;
    { Multi dead(std::move(o.Raw())); }
    d.objects.erase(obj);
    if (--g->live == 0) {
      g->finalReport = g->machine->Report();
      g->machine.reset();
    }
    return std::string();
  });
}

// ---- copies ---------------------------------------------------------------------------------
namespace {
// The host's `n` elements of `bytes` bytes each at `p` (little-endian, zero-extended; a bool
// its low bit) as raw integers into `raw`. A copy of a fixed size per element type, so the
// compiler makes it a load (a memcpy of a run-time size was a library call per element: a
// fifth of gemv's run at 2^20).
template <typename T>
void FromHostAs(const unsigned char* p, bool boolean, int64_t* raw, uint64_t n) {
  for (uint64_t i = 0; i < n; ++i) {
    T v;
    std::memcpy(&v, p + i * sizeof(T), sizeof(T));
    const uint64_t u = v;
    raw[i] = static_cast<int64_t>(boolean ? (u & 1) : u);
  }
}
void FromHost(const unsigned char* p, int bytes, bool boolean, int64_t* raw, uint64_t n) {
  switch (bytes) {
    case 1: return FromHostAs<uint8_t>(p, boolean, raw, n);
    case 2: return FromHostAs<uint16_t>(p, boolean, raw, n);
    case 4: return FromHostAs<uint32_t>(p, boolean, raw, n);
    case 8: return FromHostAs<uint64_t>(p, boolean, raw, n);
  }
  for (uint64_t i = 0; i < n; ++i) {  // any other size (none of PIMeval's types has one)
    uint64_t u = 0;
    std::memcpy(&u, p + i * bytes, size_t(bytes));
    raw[i] = static_cast<int64_t>(boolean ? (u & 1) : u);
  }
}
// The reverse: `n` raw integers into the host's elements of `bytes` bytes (their low bytes).
template <typename T>
void ToHostAs(const int64_t* raw, uint64_t n, unsigned char* p) {
  for (uint64_t i = 0; i < n; ++i) {
    const T v = static_cast<T>(static_cast<uint64_t>(raw[i]));
    std::memcpy(p + i * sizeof(T), &v, sizeof(T));
  }
}
void ToHost(const int64_t* raw, uint64_t n, int bytes, unsigned char* p) {
  switch (bytes) {
    case 1: return ToHostAs<uint8_t>(raw, n, p);
    case 2: return ToHostAs<uint16_t>(raw, n, p);
    case 4: return ToHostAs<uint32_t>(raw, n, p);
    case 8: return ToHostAs<uint64_t>(raw, n, p);
  }
  for (uint64_t i = 0; i < n; ++i) {  // any other size (none of PIMeval's types has one)
    const uint64_t u = static_cast<uint64_t>(raw[i]);
    std::memcpy(p + i * bytes, &u, size_t(bytes));
  }
}
}  // namespace

PimStatus pimCopyHostToDevice(void* src, PimObjId dest, uint64_t idxBegin, uint64_t idxEnd) {
  const double t0 = g_device ? ModelledSeconds() : 0;
  uint64_t bytes = 0;
  PimStatus s = Call("pimCopyHostToDevice", [&] {
    Object& o = Obj(dest);
    if (!src) throw UserError("the host pointer is null");
    const auto [b, e] = CopyRange(o.group->elements, idxBegin, idxEnd, dest);
    if (b == e) return std::string(TypeName(o.type));
    std::vector<int64_t> raw(e, 0);
    FromHost(static_cast<const unsigned char*>(src), o.info.bytes, o.type == PIM_BOOL,
             raw.data() + b, e - b);
    if (b == 0 && e == o.group->elements) {
      o.Raw().LoadRaw(raw);
    } else {
      Multi tmp(*o.group->machine, o.info.Fmt(), "copy");
      tmp.LoadRaw(raw);
      const Multi mask = RangeMask(*o.group, b, e);
      WhereScope w(mask);
      o.Raw() = tmp;
    }
    bytes = (e - b) * o.info.bytes;
    return std::string(TypeName(o.type));
  });
  if (s == PIM_OK) {
    g_stats.bytesToDevice += bytes;
    g_stats.secondsToDevice += ModelledSeconds() - t0;
  }
  return s;
}

PimStatus pimCopyDeviceToHost(PimObjId src, void* dest, uint64_t idxBegin, uint64_t idxEnd) {
  const double t0 = g_device ? ModelledSeconds() : 0;
  uint64_t bytes = 0;
  PimStatus s = Call("pimCopyDeviceToHost", [&] {
    Object& o = Obj(src);
    if (!dest) throw UserError("the host pointer is null");
    const auto [b, e] = CopyRange(o.group->elements, idxBegin, idxEnd, src);
    if (b == e) return std::string(TypeName(o.type));
    const std::vector<int64_t> raw = o.Raw().ReadRaw();
    ToHost(raw.data() + b, e - b, o.info.bytes, static_cast<unsigned char*>(dest));
    bytes = (e - b) * o.info.bytes;
    return std::string(TypeName(o.type));
  });
  if (s == PIM_OK) {
    g_stats.bytesToHost += bytes;
    g_stats.secondsToHost += ModelledSeconds() - t0;
  }
  return s;
}

PimStatus pimCopyDeviceToDevice(PimObjId src, PimObjId dest, uint64_t idxBegin, uint64_t idxEnd) {
  return Call("pimCopyDeviceToDevice", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    const auto [b, e] = CopyRange(a.group->elements, idxBegin, idxEnd, src);
    if (b == e) return std::string(TypeName(a.type));
    if (b == 0 && e == a.group->elements) {
      d.Raw() = a.Raw();
    } else {
      const Multi mask = RangeMask(*a.group, b, e);
      WhereScope w(mask);
      d.Raw() = a.Raw();
    }
    return std::string(TypeName(a.type));
  });
}

PimStatus pimCopyObjectToObject(PimObjId src, PimObjId dest) {
  return Call("pimCopyObjectToObject", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    d.Raw() = a.Raw();
    return std::string(TypeName(a.type));
  });
}

PimStatus pimConvertType(PimObjId src, PimObjId dest) {
  return Call("pimConvertType", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    if (a.info.isFloat || d.info.isFloat)
      throw UserError(fmt::format(
          "{} to {}: conversions from or to floating point are not emulated (PIMeval leaves them "
          "unimplemented: pimCmd.cpp convertType asserts)",
          TypeName(a.type), TypeName(d.type)));
    if (d.type == PIM_BOOL)  // a C++ conversion to bool: nonzero is true
      Store(d, Not(Equal(a.value, Uni{Zero(a.info)})));
    else
      Store(d, Convert(a.value, d.info.Fmt()));
    return fmt::format("{}->{}", a.info.name, d.info.name);
  });
}

// ---- element-wise operations -----------------------------------------------------------------
namespace {

enum class Bin { kAdd, kSub, kMul, kDiv, kAnd, kOr, kXor, kXnor, kMin, kMax, kGT, kLT, kEQ, kNE };

bool IsCompare(Bin op) { return op == Bin::kGT || op == Bin::kLT || op == Bin::kEQ || op == Bin::kNE; }
bool IsBitwise(Bin op) { return op == Bin::kAnd || op == Bin::kOr || op == Bin::kXor || op == Bin::kXnor; }

// The second operand's bit pattern as a multi: an object's, or a scalar broadcast.
const Multi& PatternOf(Machine&, const MultiFloat& y) { return y.Bits(); }
Multi PatternOf(Machine& m, const UniFloat& y) {
  return Broadcast(m, fixed::Fixed{Format::Unsigned(32, 0), BigInt(y.bits)});
}

// PIMeval's float operation (pimCmd.h, computeResultFP) of x and y — an object or a scalar —
// on the array into d, each the engine's IEEE binary32 operation (round to nearest even).
// Min and max are PIMeval's expressions, not IEEE minimumNumber: a compare and a select of
// the patterns. The binary calls take (x < y) ? x : y and (x > y) ? x : y; the …Scalar calls
// std::min(x, s) = (s < x) ? s : x and std::max(x, s) = (x < s) ? s : x (`scalarForm`):
// they differ where the two compare equal (-0 and +0) or one is NaN.
template <typename Y>
void FloatOp(Bin op, const MultiFloat& x, const Y& y, bool scalarForm, Object& d) {
  Machine& m = x.GetMachine();
  const Format pattern = Format::Unsigned(32, 0);
  switch (op) {
    case Bin::kAdd: Store(d, Add(x, y)); break;
    case Bin::kSub: Store(d, Sub(x, y)); break;
    case Bin::kMul: Store(d, Mul(x, y)); break;
    case Bin::kDiv: Store(d, Div(x, y)); break;
    case Bin::kGT: Store(d, Less(y, x)); break;
    case Bin::kLT: Store(d, Less(x, y)); break;
    case Bin::kEQ: Store(d, Equal(x, y)); break;
    case Bin::kNE: Store(d, Not(Equal(x, y))); break;
    case Bin::kMin:
    case Bin::kMax: {
      const bool isMin = op == Bin::kMin;
      const auto& yb = PatternOf(m, y);
      if (!scalarForm)
        Store(d, Select(isMin ? Less(x, y) : Less(y, x), x.Bits(), yb, pattern));
      else
        Store(d, Select(isMin ? Less(y, x) : Less(x, y), yb, x.Bits(), pattern));
      break;
    }
    default:
      throw UserError("bitwise operations do not apply to PIM_FP32 (as in PIMeval)");
  }
}

PimStatus Binary(const char* api, Bin op, PimObjId s1, PimObjId s2, PimObjId dst) {
  return Call(api, [&] {
    Object& a = Obj(s1);
    Object& b = Obj(s2);
    Object& d = Obj(dst);
    CheckSameGroup(a, b, s1, s2);
    CheckSameGroup(a, d, s1, dst);
    if (a.info.isFloat) {
      if (b.type == PIM_BOOL)
        throw UserError(fmt::format("a PIM_BOOL second source (object {}) with PIM_FP32: mixed "
                                    "floating point and BOOL operands are refused (as in PIMeval)",
                                    s2));
      CheckType(b, s2, a.type, "second source");
      CheckType(d, dst, IsCompare(op) ? PIM_BOOL : a.type, "destination");
      if (IsBitwise(op)) CheckNotFloat(a, s1, "bitwise operations");
      if (op == Bin::kDiv && Any(Equal(b.fvalue, FloatScalar(0))))
        throw UserError(fmt::format("division by zero: object {} has a zero element", s2));
      FloatOp(op, a.fvalue, b.fvalue, false, d);
      return std::string(a.info.name);
    }
    const bool boolOperand = (op == Bin::kAdd || op == Bin::kSub) && b.type == PIM_BOOL;
    if (!boolOperand) CheckType(b, s2, a.type, "second source");
    CheckType(d, dst, IsCompare(op) ? PIM_BOOL : a.type, "destination");
    const Format f = a.info.Fmt();
    const Multi& x = a.value;
    const Multi& y = b.value;
    switch (op) {
      case Bin::kAdd: Store(d, Add(x, y, f)); break;
      case Bin::kSub: Store(d, Sub(x, y, f)); break;
      case Bin::kMul: Store(d, Mul(x, y, f)); break;
      case Bin::kDiv: {
        if (Any(Equal(y, Uni{Zero(b.info)})))
          throw UserError(fmt::format("division by zero: object {} has a zero element", s2));
        if (!a.info.isSigned) {
          Store(d, Div(x, y, f));
        } else {
          const Format u = Format::Unsigned(a.info.bits, 0);
          const Multi q = Div(Abs(x, u), Abs(y, u), u);
          const Multi neg = Xor(Less(x, Uni{Zero(a.info)}), Less(y, Uni{Zero(a.info)}));
          Store(d, SignedQuotient(q, neg, f));
        }
        break;
      }
      case Bin::kAnd: Store(d, Bitwise("and", LogicOp::kAnd, x, &y, nullptr, false, f)); break;
      case Bin::kOr: Store(d, Bitwise("or", LogicOp::kOr, x, &y, nullptr, false, f)); break;
      case Bin::kXor: Store(d, Bitwise("xor", LogicOp::kXor, x, &y, nullptr, false, f)); break;
      case Bin::kXnor: Store(d, Bitwise("xnor", LogicOp::kXor, x, &y, nullptr, true, f)); break;
      case Bin::kMin: Store(d, Min(x, y, f)); break;
      case Bin::kMax: Store(d, Max(x, y, f)); break;
      case Bin::kGT: Store(d, Less(y, x)); break;
      case Bin::kLT: Store(d, Less(x, y)); break;
      case Bin::kEQ: Store(d, Equal(x, y)); break;
      case Bin::kNE: Store(d, Not(Equal(x, y))); break;
    }
    return std::string(a.info.name);
  });
}

PimStatus Scalar(const char* api, Bin op, PimObjId s, PimObjId dst, uint64_t scalar) {
  return Call(api, [&] {
    Object& a = Obj(s);
    Object& d = Obj(dst);
    CheckSameGroup(a, d, s, dst);
    CheckType(d, dst, IsCompare(op) ? PIM_BOOL : a.type, "destination");
    if (a.info.isFloat) {
      if (IsBitwise(op)) CheckNotFloat(a, s, "bitwise operations");
      if (op == Bin::kDiv && FloatOf(scalar) == 0.0f)
        throw UserError("division by zero: the scalar is 0");
      FloatOp(op, a.fvalue, FloatScalar(scalar), true, d);
      return std::string(a.info.name);
    }
    const Format f = a.info.Fmt();
    const Multi& x = a.value;
    const Uni w{Wrapped(a.info, scalar)};
    const Uni e{Exact(a.info, scalar)};
    switch (op) {
      case Bin::kAdd: Store(d, Add(x, w, f)); break;
      case Bin::kSub: Store(d, Sub(x, w, f)); break;
      case Bin::kMul: Store(d, Mul(x, w, f)); break;
      case Bin::kDiv: {
        if (scalar == 0) throw UserError("division by zero: the scalar is 0");
        if (!a.info.isSigned) {
          Store(d, Div(x, e, f));
        } else {
          const Format u = Format::Unsigned(a.info.bits, 0);
          const int64_t sv = static_cast<int64_t>(scalar);
          const uint64_t mag = sv < 0 ? uint64_t(0) - scalar : scalar;
          const fixed::Fixed m = mag <= (uint64_t{1} << (a.info.bits - 1))
                                     ? fixed::Fixed{u, BigInt(mag)}
                                     : fixed::Fixed{Format::Unsigned(64, 0), BigInt(mag)};
          const Multi q = Div(Abs(x, u), Uni{m}, u);
          // Negative where the element's sign differs from the scalar's.
          const Multi neg = sv < 0 ? LessEqual(Uni{Zero(a.info)}, x) : Less(x, Uni{Zero(a.info)});
          Store(d, SignedQuotient(q, neg, f));
        }
        break;
      }
      case Bin::kAnd: Store(d, Bitwise("and", LogicOp::kAnd, x, nullptr, &w.value, false, f)); break;
      case Bin::kOr: Store(d, Bitwise("or", LogicOp::kOr, x, nullptr, &w.value, false, f)); break;
      case Bin::kXor: Store(d, Bitwise("xor", LogicOp::kXor, x, nullptr, &w.value, false, f)); break;
      case Bin::kXnor: Store(d, Bitwise("xnor", LogicOp::kXor, x, nullptr, &w.value, true, f)); break;
      case Bin::kMin: Store(d, Min(x, e, f)); break;
      case Bin::kMax: Store(d, Max(x, e, f)); break;
      case Bin::kGT: Store(d, Less(e, x)); break;
      case Bin::kLT: Store(d, Less(x, e)); break;
      case Bin::kEQ: Store(d, Equal(x, e)); break;
      case Bin::kNE: Store(d, Not(Equal(x, e))); break;
    }
    return std::string(a.info.name);
  });
}

}  // namespace

PimStatus pimAdd(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimAdd", Bin::kAdd, a, b, d); }
PimStatus pimSub(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimSub", Bin::kSub, a, b, d); }
PimStatus pimMul(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimMul", Bin::kMul, a, b, d); }
PimStatus pimDiv(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimDiv", Bin::kDiv, a, b, d); }
PimStatus pimAnd(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimAnd", Bin::kAnd, a, b, d); }
PimStatus pimOr(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimOr", Bin::kOr, a, b, d); }
PimStatus pimXor(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimXor", Bin::kXor, a, b, d); }
PimStatus pimXnor(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimXnor", Bin::kXnor, a, b, d); }
PimStatus pimMin(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimMin", Bin::kMin, a, b, d); }
PimStatus pimMax(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimMax", Bin::kMax, a, b, d); }
PimStatus pimGT(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimGT", Bin::kGT, a, b, d); }
PimStatus pimLT(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimLT", Bin::kLT, a, b, d); }
PimStatus pimEQ(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimEQ", Bin::kEQ, a, b, d); }
PimStatus pimNE(PimObjId a, PimObjId b, PimObjId d) { return Binary("pimNE", Bin::kNE, a, b, d); }

PimStatus pimAddScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimAddScalar", Bin::kAdd, a, d, s); }
PimStatus pimSubScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimSubScalar", Bin::kSub, a, d, s); }
PimStatus pimMulScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimMulScalar", Bin::kMul, a, d, s); }
PimStatus pimDivScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimDivScalar", Bin::kDiv, a, d, s); }
PimStatus pimAndScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimAndScalar", Bin::kAnd, a, d, s); }
PimStatus pimOrScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimOrScalar", Bin::kOr, a, d, s); }
PimStatus pimXorScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimXorScalar", Bin::kXor, a, d, s); }
PimStatus pimXnorScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimXnorScalar", Bin::kXnor, a, d, s); }
PimStatus pimMinScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimMinScalar", Bin::kMin, a, d, s); }
PimStatus pimMaxScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimMaxScalar", Bin::kMax, a, d, s); }
PimStatus pimGTScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimGTScalar", Bin::kGT, a, d, s); }
PimStatus pimLTScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimLTScalar", Bin::kLT, a, d, s); }
PimStatus pimEQScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimEQScalar", Bin::kEQ, a, d, s); }
PimStatus pimNEScalar(PimObjId a, PimObjId d, uint64_t s) { return Scalar("pimNEScalar", Bin::kNE, a, d, s); }

PimStatus pimAbs(PimObjId src, PimObjId dest) {
  return Call("pimAbs", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    if (a.info.isFloat) {
      // PIMeval's (x < 0) ? -x : x: the sign bit flipped where x < 0 (so -0 and a NaN keep
      // theirs): a compare with the uni 0, the pattern copied, its sign row XORed.
      const Multi negative = Less(a.fvalue, FloatScalar(0));
      Multi r = a.fvalue.Bits();
      Machine& m = r.GetMachine();
      m.Kernels().logic(LogicOp::kXor, r.Plane(31), negative.Plane(0), r.Plane(31),
                        m.WordsPerPlane());
      m.Charge("fabs", bitserial::LogicCost({bitserial::BoolFormat(), r.GetSpace(), false}, true,
                                            r.GetSpace()));
      Store(d, std::move(r));
    } else if (a.info.isSigned)
      Store(d, Abs(a.value, a.info.Fmt()));
    else
      d.value = a.value;
    return std::string(a.info.name);
  });
}

PimStatus pimNot(PimObjId src, PimObjId dest) {
  return Call("pimNot", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    CheckNotFloat(a, src, "bitwise operations");
    Store(d, Bitwise("not", LogicOp::kNot, a.value, nullptr, nullptr, false, a.info.Fmt()));
    return std::string(a.info.name);
  });
}

PimStatus pimScaledAdd(PimObjId src1, PimObjId src2, PimObjId dest, uint64_t scalarValue) {
  return Call("pimScaledAdd", [&] {
    Object& a = Obj(src1);
    Object& b = Obj(src2);
    Object& d = Obj(dest);
    CheckSameGroup(a, b, src1, src2);
    CheckSameGroup(a, d, src1, dest);
    CheckType(b, src2, a.type, "second source");
    CheckType(d, dest, a.type, "destination");
    if (a.info.isFloat) {  // (x * s) + y, rounded twice as PIMeval's float expression
      Store(d, Add(Mul(a.fvalue, FloatScalar(scalarValue)), b.fvalue));
      return std::string(a.info.name);
    }
    const Format f = a.info.Fmt();
    Store(d, Add(Mul(a.value, Uni{Wrapped(a.info, scalarValue)}, f), b.value, f));
    return std::string(a.info.name);
  });
}

PimStatus pimPopCount(PimObjId src, PimObjId dest) {
  return Call("pimPopCount", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    CheckNotFloat(a, src, "bit counts");
    Multi acc = Slice(a.value, 0);
    for (int i = 1; i < a.info.bits; ++i) {
      int bits = 1;
      while ((1 << bits) < i + 2) ++bits;  // holds 0..i+1
      Multi next = Add(acc, Slice(a.value, i), Format::Unsigned(bits, 0));
      std::swap(acc, next);
    }
    Store(d, Convert(acc, a.info.Fmt()));
    return std::string(a.info.name);
  });
}

PimStatus pimPrefixSum(PimObjId src, PimObjId dest) {
  return Call("pimPrefixSum", [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    CheckNotFloat(a, src,
                  "prefix sums here (PIMeval adds floats in element order, one after another; "
                  "the array's log-step scan would round differently, so it is not emulated)");
    const Format f = a.info.Fmt();
    Multi s = a.value;
    // Hillis–Steele: log2 n shift-and-add steps along the chain of elements (a PE whose
    // source is before element 0 receives 0).
    for (uint64_t k = 1; k < a.group->elements; k *= 2) {
      Multi next = Add(s, ShiftElements(s, static_cast<int>(k), a.group->elements), f);
      std::swap(s, next);
    }
    Store(d, std::move(s));
    return std::string(a.info.name);
  });
}

// PIMeval runs pimMAC on PIM_DEVICE_AIM only ("only supported on AiM", pimCmd.cpp, pimCmdMAC):
// its per-core results are AiM's banks, its second operand the global buffer above.
PimStatus pimMAC(PimObjId, PimObjId, void*) {
  return Refuse("pimMAC",
                "the multiply-accumulate over the global buffer into per-core results runs on "
                "PIM_DEVICE_AIM only (PIMeval refuses it on every other simulation target: \"only "
                "supported on AiM\"); AiM is bit-parallel, not emulated here");
}

// ---- reductions -------------------------------------------------------------------------------
namespace {
enum class Red { kSum, kMin, kMax };

// A PIM_FP32 reduction of [b, e) folded into *out (a float), PIMeval's way where its order
// does not matter and in a documented order where it does (docs/pim.md, "Semantics"):
//  * the range is reduced as a tree by element index: at step k (s = 2^k, while s < e)
//    element i combines with element i + s, so element 0 ends with the range's pairwise
//    combination. The array takes the steps within a region (s below the region's elements:
//    the chain moves the partner s places, as a subarray's columns can); the host reads the
//    partials (every plane) and takes the steps across regions, as PIMeval folds its regions'
//    results on the host — the same tree, so the same result. Where the elements cannot move
//    (part of a layer of a 2-D mesh or of several layers) the host takes every step;
//  * sums: elements outside the range are +0.0; the host then adds (+0.0 + tree) to *out.
//    PIMeval adds one element after another per region from a +0.0 seed, then the regions
//    into *out: the same up to the rounding of a different association;
//  * min/max: PIMeval's `cur > x ? x : cur` (max: `cur < x ? x : cur`) from a seed of
//    FLT_MAX (max: -FLT_MAX) per region keeps the first of the smallest values and skips
//    NaN elements; the tree keeps the left operand on ties with NaN and out-of-range
//    elements set to the seed, so it selects the same element; the host folds
//    seed then tree into *out with PIMeval's expression (a NaN at *out stays).
void FloatReduce(Red op, Object& a, void* out, uint64_t b, uint64_t e) {
  Group& g = *a.group;
  Machine& m = *g.machine;
  const uint64_t n = g.elements;
  const float seed = op == Red::kSum ? 0.0f
                     : op == Red::kMin ? std::numeric_limits<float>::max()
                                       : std::numeric_limits<float>::lowest();
  float tree = seed;
  if (b < e) {
    const MultiFloat id = Broadcast(m, FloatScalar(BitsOf(seed)));
    MultiFloat x = a.fvalue;
    const bool ranged = !(b == 0 && e == n);
    if (ranged || op != Red::kSum) {
      // The elements that take the seed: outside the range; for min/max NaN too.
      std::optional<Multi> off;
      if (ranged) off.emplace(Not(RangeMask(g, b, e)));
      if (op != Red::kSum) {
        Multi nan = Not(Equal(x, x));
        off.emplace(off ? Or(*off, nan) : std::move(nan));
      }
      WhereScope w(*off);
      x.Bits() = id.Bits();
    }
    const uint64_t arraySteps = ElementsCanMove(m, n) ? g.regionElements : 1;
    uint64_t s = 1;
    for (; s < e && s < arraySteps; s *= 2) {
      MultiFloat y = AsFloat(ShiftElements(x.Bits(), -static_cast<int>(s), n));
      if (op != Red::kSum) {  // partners past the end (the chain brings +0.0) are the seed
        const Multi past = RangeMask(g, n - s, n);
        WhereScope w(past);
        y.Bits() = id.Bits();
      }
      if (op == Red::kSum)
        x = Add(x, y);
      else  // min: y < x ? y : x; max: x < y ? y : x (x, the left one, kept on ties)
        x = AsFloat(Select(op == Red::kMin ? Less(y, x) : Less(x, y), y.Bits(), x.Bits(),
                           Format::Unsigned(32, 0)));
    }
    if (s >= e) {
      tree = FloatOf(ReadElement(g, x.Bits(), 0).raw.convert_to<uint64_t>());
    } else {
      const std::vector<int64_t> raw = x.Bits().ReadRaw();
      std::vector<float> h(n);
      for (uint64_t i = 0; i < n; ++i) h[i] = FloatOf(static_cast<uint64_t>(raw[i]));
      for (; s < e; s *= 2)
        for (uint64_t i = 0; i < n; i += 2 * s) {
          const float y = i + s < n ? h[i + s] : seed;  // past the end: the seed, as the chain
          // brings +0.0 and the min/max steps set it
          h[i] = op == Red::kSum ? h[i] + y : op == Red::kMin ? (y < h[i] ? y : h[i])
                                                               : (h[i] < y ? y : h[i]);
        }
      tree = h[0];
      if (std::isnan(tree)) tree = FloatOf(0x7fc00000);  // the engine's NaN (docs/pim.md)
    }
  }
  float cur;
  std::memcpy(&cur, out, 4);
  if (op == Red::kSum) {
    cur = cur + (0.0f + tree);
  } else {
    for (float r : {seed, tree})
      cur = op == Red::kMin ? (cur > r ? r : cur) : (cur < r ? r : cur);
  }
  std::memcpy(out, &cur, 4);
}

PimStatus Reduce(const char* api, Red op, PimObjId src, void* out, uint64_t b0, uint64_t e0) {
  return Call(api, [&] {
    Object& a = Obj(src);
    if (!out) throw UserError("the result pointer is null");
    const auto [b, e] = ReductionRange(a.group->elements, b0, e0, src);
    if (a.info.isFloat) {
      FloatReduce(op, a, out, b, e);
      return std::string(a.info.name);
    }
    const bool ranged = !(b == 0 && e == a.group->elements);
    std::optional<Multi> mask;
    std::optional<WhereScope> where;
    if (ranged) {
      mask.emplace(RangeMask(*a.group, b, e));
      where.emplace(*mask);
    }
    if (op == Red::kSum) {
      const BigInt sum = ReduceSum(a.value).raw;
      // Into the accumulator as PIMeval adds: modulo 2^64.
      const uint64_t v = LowBits(sum, 64);
      if (a.info.isSigned) {
        int64_t acc;
        std::memcpy(&acc, out, 8);
        acc = static_cast<int64_t>(static_cast<uint64_t>(acc) + v);
        std::memcpy(out, &acc, 8);
      } else {
        uint64_t acc;
        std::memcpy(&acc, out, 8);
        acc += v;
        std::memcpy(out, &acc, 8);
      }
    } else {
      if (e == b) return std::string(a.info.name);  // an empty range keeps *out
      const BigInt r = (op == Red::kMin ? ReduceMin(a.value) : ReduceMax(a.value)).raw;
      // The value at *out, as the object's C type.
      uint64_t bits = 0;
      std::memcpy(&bits, out, a.info.bytes);
      BigInt cur = BigInt(LowBits(BigInt(bits), a.info.bits));
      if (a.info.isSigned && cur > a.info.Fmt().MaxRaw()) cur -= BigInt(1) << a.info.bits;
      const BigInt best = op == Red::kMin ? (r < cur ? r : cur) : (r > cur ? r : cur);
      const uint64_t w = LowBits(best, a.info.bits);
      std::memcpy(out, &w, a.info.bytes);
    }
    return std::string(a.info.name);
  });
}
}  // namespace

PimStatus pimRedSum(PimObjId src, void* sum, uint64_t b, uint64_t e) {
  return Reduce("pimRedSum", Red::kSum, src, sum, b, e);
}
PimStatus pimRedMin(PimObjId src, void* min, uint64_t b, uint64_t e) {
  return Reduce("pimRedMin", Red::kMin, src, min, b, e);
}
PimStatus pimRedMax(PimObjId src, void* max, uint64_t b, uint64_t e) {
  return Reduce("pimRedMax", Red::kMax, src, max, b, e);
}

// ---- bit slices, conditionals, broadcasts, element moves -------------------------------------
PimStatus pimBitSliceExtract(PimObjId src, PimObjId destBool, unsigned bitIdx) {
  return Call("pimBitSliceExtract", [&] {
    Object& a = Obj(src);
    Object& d = Obj(destBool);
    CheckSameGroup(a, d, src, destBool);
    CheckType(d, destBool, PIM_BOOL, "destination");
    if (bitIdx >= unsigned(a.info.bits))
      throw UserError(fmt::format("bit index {} is outside {}'s {} bits", bitIdx, TypeName(a.type),
                                  a.info.bits));
    Store(d, Slice(a.Raw(), int(bitIdx)));
    return std::string(a.info.name);
  });
}

PimStatus pimBitSliceInsert(PimObjId srcBool, PimObjId dest, unsigned bitIdx) {
  return Call("pimBitSliceInsert", [&] {
    Object& a = Obj(srcBool);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, srcBool, dest);
    CheckType(a, srcBool, PIM_BOOL, "source");
    if (bitIdx >= unsigned(d.info.bits))
      throw UserError(fmt::format("bit index {} is outside {}'s {} bits", bitIdx, TypeName(d.type),
                                  d.info.bits));
    // One row copied into row bitIdx of the destination, in every active PE.
    Machine& m = d.Raw().GetMachine();
    const std::vector<Word> before(d.Raw().Plane(int(bitIdx)),
                                   d.Raw().Plane(int(bitIdx)) + m.WordsPerPlane());
    Word* row = d.Raw().Plane(int(bitIdx));
    const Word* act = m.Activity();
    for (size_t w = 0; w < m.WordsPerPlane(); ++w)
      row[w] = (a.Raw().Plane(0)[w] & act[w]) | (before[w] & ~act[w]);
    m.Charge("bitSliceInsert", bitserial::CopyCost(a.Raw().AsOperand(),
                                                   {bitserial::BoolFormat(), d.Raw().GetSpace(), false}));
    return std::string(d.info.name);
  });
}

PimStatus pimCondCopy(PimObjId condBool, PimObjId src, PimObjId dest) {
  return Call("pimCondCopy", [&] {
    Object& c = Obj(condBool);
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(c, a, condBool, src);
    CheckSameGroup(c, d, condBool, dest);
    CheckType(c, condBool, PIM_BOOL, "condition");
    CheckType(d, dest, a.type, "destination");
    WhereScope w(c.value);
    d.Raw() = a.Raw();
    return std::string(a.info.name);
  });
}

PimStatus pimCondBroadcast(PimObjId condBool, uint64_t scalarBits, PimObjId dest) {
  return Call("pimCondBroadcast", [&] {
    Object& c = Obj(condBool);
    Object& d = Obj(dest);
    CheckSameGroup(c, d, condBool, dest);
    CheckType(c, condBool, PIM_BOOL, "condition");
    const Multi v = Broadcast(*d.group->machine, Wrapped(d.info, scalarBits));
    WhereScope w(c.value);
    d.Raw() = v;
    return std::string(d.info.name);
  });
}

PimStatus pimCondSelect(PimObjId condBool, PimObjId src1, PimObjId src2, PimObjId dest) {
  return Call("pimCondSelect", [&] {
    Object& c = Obj(condBool);
    Object& a = Obj(src1);
    Object& b = Obj(src2);
    Object& d = Obj(dest);
    CheckSameGroup(c, a, condBool, src1);
    CheckSameGroup(c, b, condBool, src2);
    CheckSameGroup(c, d, condBool, dest);
    CheckType(c, condBool, PIM_BOOL, "condition");
    CheckType(b, src2, a.type, "second source");
    CheckType(d, dest, a.type, "destination");
    Store(d, Select(c.value, a.Raw(), b.Raw(), a.info.Fmt()));
    return std::string(a.info.name);
  });
}

PimStatus pimCondSelectScalar(PimObjId condBool, PimObjId src1, uint64_t scalarBits,
                              PimObjId dest) {
  return Call("pimCondSelectScalar", [&] {
    Object& c = Obj(condBool);
    Object& a = Obj(src1);
    Object& d = Obj(dest);
    CheckSameGroup(c, a, condBool, src1);
    CheckSameGroup(c, d, condBool, dest);
    CheckType(c, condBool, PIM_BOOL, "condition");
    CheckType(d, dest, a.type, "destination");
    const Multi v = Broadcast(*a.group->machine, Wrapped(a.info, scalarBits));
    Store(d, Select(c.value, a.Raw(), v, a.info.Fmt()));
    return std::string(a.info.name);
  });
}

PimStatus pimBroadcastInt(PimObjId dest, int64_t value) {
  return Call("pimBroadcastInt", [&] {
    Object& d = Obj(dest);
    Store(d, Broadcast(*d.group->machine, Wrapped(d.info, static_cast<uint64_t>(value))));
    return std::string(d.info.name);
  });
}
PimStatus pimBroadcastUInt(PimObjId dest, uint64_t value) {
  return Call("pimBroadcastUInt", [&] {
    Object& d = Obj(dest);
    Store(d, Broadcast(*d.group->machine, Wrapped(d.info, value)));
    return std::string(d.info.name);
  });
}
// The float's bit pattern into every element (PIMeval's castTypeToBits: into a narrower
// type, its low bits).
PimStatus pimBroadcastFP(PimObjId dest, float value) {
  return Call("pimBroadcastFP", [&] {
    Object& d = Obj(dest);
    Store(d, Broadcast(*d.group->machine, Wrapped(d.info, BitsOf(value))));
    return std::string(d.info.name);
  });
}

namespace {
// Moves the object's elements one place (right: i -> i+1); a rotate brings the element moved
// off one end in at the other (read to the host by a masked reduction and broadcast back).
PimStatus MoveElements(const char* api, PimObjId src, bool right, bool rotate) {
  return Call(api, [&] {
    Object& a = Obj(src);
    const uint64_t n = a.group->elements;
    Group& g = *a.group;
    std::optional<fixed::Fixed> off;
    if (rotate) off = ReadElement(g, a.Raw(), right ? n - 1 : 0);
    Multi r = ShiftElements(a.Raw(), right ? 1 : -1, n);
    {
      // The element entering at the end: 0, or the one rotated round.
      const Multi in = right ? RangeMask(g, 0, 1) : RangeMask(g, n - 1, n);
      const fixed::Fixed v = off ? fixed::Fixed::FromBits(a.info.Fmt(), off->Bits())
                                 : Zero(a.info);
      const Multi b = Broadcast(*g.machine, v);
      WhereScope w(in);
      r = b;
    }
    a.Raw() = std::move(r);
    return std::string(a.info.name);
  });
}
}  // namespace

PimStatus pimRotateElementsRight(PimObjId src) { return MoveElements("pimRotateElementsRight", src, true, true); }
PimStatus pimRotateElementsLeft(PimObjId src) { return MoveElements("pimRotateElementsLeft", src, false, true); }
PimStatus pimShiftElementsRight(PimObjId src) { return MoveElements("pimShiftElementsRight", src, true, false); }
PimStatus pimShiftElementsLeft(PimObjId src) { return MoveElements("pimShiftElementsLeft", src, false, false); }

namespace {
PimStatus ShiftBits(const char* api, PimObjId src, PimObjId dest, unsigned k, bool left) {
  return Call(api, [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(d, dest, a.type, "destination");
    CheckNotFloat(a, src, "bit shifts");
    // Past the width every shift gives the same as by the width (0, or the sign for a signed
    // right shift: floor(a / 2^k)).
    const int s = static_cast<int>(std::min<unsigned>(k, unsigned(a.info.bits)));
    Store(d, Shift(a.value, left ? s : -s, a.info.Fmt()));
    return std::string(a.info.name);
  });
}
}  // namespace

PimStatus pimShiftBitsRight(PimObjId src, PimObjId dest, unsigned k) {
  return ShiftBits("pimShiftBitsRight", src, dest, k, false);
}
PimStatus pimShiftBitsLeft(PimObjId src, PimObjId dest, unsigned k) {
  return ShiftBits("pimShiftBitsLeft", src, dest, k, true);
}

namespace {
// dest = lut[src]: per entry, the elements equal to it take its value (a compare with a uni and
// a masked broadcast), 256 of each whatever the element count.
PimStatus Lookup(const char* api, PimObjId src, PimObjId dest, const std::vector<uint8_t>& lut) {
  return Call(api, [&] {
    Object& a = Obj(src);
    Object& d = Obj(dest);
    CheckSameGroup(a, d, src, dest);
    CheckType(a, src, PIM_UINT8, "source");
    CheckType(d, dest, PIM_UINT8, "destination");
    if (lut.size() != 256)
      throw UserError(fmt::format("the lookup table has {} entries, expected 256", lut.size()));
    Machine& m = *a.group->machine;
    Multi r(m, a.info.Fmt(), "sbox");
    for (int v = 0; v < 256; ++v) {
      const Multi hit = Equal(a.value, Uni{fixed::Fixed{a.info.Fmt(), v}});
      const Multi val = Broadcast(m, fixed::Fixed{a.info.Fmt(), lut[v]});
      WhereScope w(hit);
      r = val;
    }
    d.value = std::move(r);
    return std::string(a.info.name);
  });
}
}  // namespace

PimStatus pimAesSbox(PimObjId src, PimObjId dest, const std::vector<uint8_t>& lut) {
  return Lookup("pimAesSbox", src, dest, lut);
}
PimStatus pimAesInverseSbox(PimObjId src, PimObjId dest, const std::vector<uint8_t>& lut) {
  return Lookup("pimAesInverseSbox", src, dest, lut);
}

PimStatus pimFuse(PimProg prog) {
  for (auto& f : prog.m_apis)
    if (f() != PIM_OK) return PIM_ERROR;
  return PIM_OK;
}

// PIMeval's copies take the copy type and do not use it (pimCmd.cpp, pimCmdCopy: elements are
// copied by index and charged by bytes whatever the layout): PIM_COPY_V and PIM_COPY_H are the
// plain copy; another value is an error.
PimStatus pimCopyHostToDeviceWithType(PimCopyEnum copyType, void* src, PimObjId dest,
                                      uint64_t idxBegin, uint64_t idxEnd) {
  if (copyType != PIM_COPY_V && copyType != PIM_COPY_H)
    return Refuse("pimCopyHostToDeviceWithType",
                  fmt::format("copy type {} is not a PimCopyEnum", int(copyType)));
  return pimCopyHostToDevice(src, dest, idxBegin, idxEnd);
}
PimStatus pimCopyDeviceToHostWithType(PimCopyEnum copyType, PimObjId src, void* dest,
                                      uint64_t idxBegin, uint64_t idxEnd) {
  if (copyType != PIM_COPY_V && copyType != PIM_COPY_H)
    return Refuse("pimCopyDeviceToHostWithType",
                  fmt::format("copy type {} is not a PimCopyEnum", int(copyType)));
  return pimCopyDeviceToHost(src, dest, idxBegin, idxEnd);
}

PimObjId pimCreateDualContactRef(PimObjId) {
  Refuse("pimCreateDualContactRef", "references to an object's negation are not supported");
  return -1;
}
PimObjId pimCreateRangedRef(PimObjId, uint64_t, uint64_t) {
  Refuse("pimCreateRangedRef", "ranged references are not supported (nor in PIMeval)");
  return -1;
}

#define ZEPHYR_PIM_MICRO_OP(name, ...)                                                    \
  PimStatus name(__VA_ARGS__) {                                                           \
    return Refuse(#name,                                                                  \
                  "BitSIMD-V/SIMDRAM micro-op programming is not supported: write the "  \
                  "program with the element-wise operations (docs/pim.md)");              \
  }
ZEPHYR_PIM_MICRO_OP(pimOpReadRowToSa, PimObjId, unsigned)
ZEPHYR_PIM_MICRO_OP(pimOpWriteSaToRow, PimObjId, unsigned)
ZEPHYR_PIM_MICRO_OP(pimOpTRA, PimObjId, unsigned, PimObjId, unsigned, PimObjId, unsigned)
ZEPHYR_PIM_MICRO_OP(pimOpMove, PimObjId, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpSet, PimObjId, PimRowReg, bool)
ZEPHYR_PIM_MICRO_OP(pimOpNot, PimObjId, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpAnd, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpOr, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpNand, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpNor, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpXor, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpXnor, PimObjId, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpMaj, PimObjId, PimRowReg, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpSel, PimObjId, PimRowReg, PimRowReg, PimRowReg, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpRotateRH, PimObjId, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpRotateLH, PimObjId, PimRowReg)
ZEPHYR_PIM_MICRO_OP(pimOpAP, int, ...)
ZEPHYR_PIM_MICRO_OP(pimOpAAP, int, int, ...)
