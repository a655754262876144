#include "bitserial/profile.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fixed/check.h"
#include "fixed/input_file.h"

namespace zephyr::bitserial {

namespace {
constexpr const char* kMicroOpNames[kMicroOpCount] = {
    "readInternal", "writeInternal",   "readExternal",     "writeExternal", "aluStep",
    "flagOp",       "accumulatorRead", "accumulatorWrite", "activitySet",   "meshHop",
    "reduceBit",    "broadcastBit",    "hostPlane"};
constexpr const char* kClassNames[kCycleClassCount] = {
    "alu", "internalMemory", "externalMemory", "communication", "reduction", "host"};

// ---- The built-in profiles: bitserial/profiles/*.json, assembled into the binary ------------
// Each file's bytes and a terminating NUL become a hidden symbol (the assembler's .incbin, with
// the path relative to the repository root, where every build compiles). The Makefile makes
// this object depend on the files; ccache does not cache a source with .incbin.
#define ZEPHYR_EMBED_PROFILE(symbol, path)                                                 \
  __asm__(".pushsection .rodata\n.global " #symbol "\n.hidden " #symbol "\n.type " #symbol \
          ", @object\n" #symbol ":\n.incbin \"" path "\"\n.byte 0\n.size " #symbol         \
          ", . - " #symbol "\n.popsection\n");                                             \
  extern "C" const char symbol[];
ZEPHYR_EMBED_PROFILE(zephyr_profile_blitzen, "bitserial/profiles/blitzen.json")
ZEPHYR_EMBED_PROFILE(zephyr_profile_mpp, "bitserial/profiles/mpp.json")
ZEPHYR_EMBED_PROFILE(zephyr_profile_pim_bitsimd_v_bank,
                     "bitserial/profiles/pim-bitsimd-v-bank.json")
ZEPHYR_EMBED_PROFILE(zephyr_profile_wavetracer, "bitserial/profiles/wavetracer.json")

const std::map<std::string, std::string>& BuiltIns() {
  static const std::map<std::string, std::string> builtIns = {
      {"blitzen", zephyr_profile_blitzen},
      {"mpp", zephyr_profile_mpp},
      {"pim-bitsimd-v-bank", zephyr_profile_pim_bitsimd_v_bank},
      {"wavetracer", zephyr_profile_wavetracer}};
  return builtIns;
}

// ---- Where each key and value of a JSON text is: line and column by path --------------------
// nlohmann's values carry no position, so the (already parsed, hence valid) text is scanned
// once: every object key and every value gets its 1-based line and column, by dotted path
// ("entries.readInternal.value", "entries.meshShapes.value.1").
struct Position {
  int line = 1, column = 1;
};
struct Positions {
  std::map<std::string, Position> key, value;
  // The first key that appears twice in one object (nlohmann would keep the last silently),
  // and where it appears the second time.
  std::string duplicate;
  Position duplicateAt;
};
Positions KeyPositions(const std::string& text) {
  Positions at;
  struct Frame {
    bool object;
    std::string base;  // the container's own path
    std::string key;   // objects: the current key
    int index = 0;     // arrays: the current element
    bool expectKey = true;
  };
  std::vector<Frame> stack;
  auto join = [](const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  };
  // The path of the value being read in the innermost container ("" at the top).
  auto current = [&] {
    if (stack.empty()) return std::string();
    const Frame& f = stack.back();
    return join(f.base, f.object ? f.key : std::to_string(f.index));
  };
  Position pos;
  auto advance = [&](char c) {
    if (c == '\n') {
      ++pos.line;
      pos.column = 1;
    } else {
      ++pos.column;
    }
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const Position start = pos;
    if (c == '"') {
      std::string s;
      advance(c);
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') advance(text[i++]);
        s += text[i];
        advance(text[i]);
      }
      advance('"');
      if (!stack.empty() && stack.back().object && stack.back().expectKey) {
        stack.back().key = s;
        stack.back().expectKey = false;
        if (!at.key.emplace(current(), start).second && at.duplicate.empty()) {
          at.duplicate = current();
          at.duplicateAt = start;
        }
      } else {
        at.value.emplace(current(), start);
      }
      continue;
    }
    if (c == '{' || c == '[') {
      at.value.emplace(current(), start);
      stack.push_back(Frame{.object = c == '{', .base = current(), .key = {}});
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();  // nlohmann refused an unbalanced text already
    } else if (c == ',' && !stack.empty()) {
      if (stack.back().object)
        stack.back().expectKey = true;
      else
        ++stack.back().index;
    } else if (c != ':' && !std::isspace(static_cast<unsigned char>(c))) {
      // A number, true, false or null: one token.
      at.value.emplace(current(), start);
      while (i + 1 < text.size() && !std::strchr(",]} \t\r\n", text[i + 1])) advance(text[i++]);
    }
    advance(text[i]);
  }
  return at;
}

// Line and column of a byte offset (nlohmann's parse errors give one).
Position PositionOf(const std::string& text, size_t byte) {
  Position p;
  for (size_t i = 0; i < std::min(byte, text.size()); ++i) {
    if (text[i] == '\n') {
      ++p.line;
      p.column = 1;
    } else {
      ++p.column;
    }
  }
  return p;
}

double ParseNumber(const std::string& text, const std::string& what) {
  // A plain decimal number as a profile file writes one: strtod alone would also take a
  // leading space, hexadecimal ("0x10"), "inf" and "nan".
  const bool decimal = !text.empty() && text.size() <= 64 &&
                       (std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '.') &&
                       text.find_first_not_of("0123456789.eE+-") == std::string::npos;
  char* end = nullptr;
  double v = decimal ? std::strtod(text.c_str(), &end) : 0;
  if (!decimal || end != text.c_str() + text.size() || !(v >= 0) || !std::isfinite(v))
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

namespace {
// The entries of a profile file, in the file's order: name, unit, and for the numbers the
// range a value must lie in (docs/bitserial.md, "Machine profiles").
struct EntrySpec {
  const char* name;
  const char* unit;
};
constexpr EntrySpec kGeometry[] = {{"clockHz", "Hz"},
                                   {"physicalPes", "PEs"},
                                   {"internalBitsPerPe", "bits"},
                                   {"externalBitsPerPe", "bits"},
                                   {"meshShapes", "PEs per axis, x fastest"},
                                   {"floatSubnormals", "flag"}};
constexpr int kGeometryEntries = 6;

// What is wrong with `v` as the value of the numeric entry `key` ("" when nothing is); the one
// rule for a file's entries and for --set.
std::string RangeError(const std::string& key, double v) {
  if (!std::isfinite(v)) return "expected a finite number";
  // At least 1 Hz: a clock of 1e-320 Hz would make every modelled time infinite.
  if (key == "clockHz") return v >= 1 && v <= 1e12 ? "" : "expected a clock from 1 Hz to 1e12 Hz";
  if (key == "physicalPes")
    return v == std::floor(v) && v >= 512 && v <= 0x1p24 && std::fmod(v, 512) == 0
               ? ""
               // The kernels load whole, aligned vectors of the widest target (8 words of 64
               // PEs on AVX-512), so a layer is a whole number of them (docs/bitserial.md).
               : "expected a positive multiple of 512 PEs, up to 2^24";
  if (key == "internalBitsPerPe" || key == "externalBitsPerPe")
    // At most 2^40 per PE (far beyond any machine; the cast to int64_t stays defined).
    return v == std::floor(v) && v >= 0 && v <= 0x1p40
               ? ""
               : "expected a whole number of bits from 0 to 2^40";
  if (key == "floatSubnormals") return v == 0 || v == 1 ? "" : "expected 0 or 1";
  return v >= 0 && v <= 1e9 ? "" : "expected a cost from 0 to 1e9 cycles";
}

// "64x128" -> {64, 128}; empty on a malformed shape or one of more than 2^24 PEs (the most a
// profile may have: the product is taken in 64 bits, so "8192x524289" cannot wrap around).
std::vector<int> ParseShape(const std::string& text) {
  std::vector<int> extent;
  int64_t pes = 1;
  size_t at = 0;
  while (at <= text.size()) {
    size_t x = text.find('x', at);
    if (x == std::string::npos) x = text.size();
    const std::string part = text.substr(at, x - at);
    if (part.empty() || part.size() > 8 ||
        part.find_first_not_of("0123456789") != std::string::npos)
      return {};
    extent.push_back(std::stoi(part));
    if (extent.back() <= 0) return {};
    pes *= extent.back();
    if (pes > (int64_t{1} << 24)) return {};
    at = x + 1;
  }
  return extent.size() <= 4 ? extent : std::vector<int>{};
}

// A number as a profile file writes it: whole values without a fraction.
std::string NumberText(double v) {
  if (v == std::floor(v) && std::fabs(v) < 0x1p53)
    return fmt::format("{}", static_cast<int64_t>(v));
  return fmt::format("{}", v);
}

class ProfileReader {
 public:
  ProfileReader(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  MachineProfile Read() {
    // Bounded before nlohmann sees it: the size, and the nesting (a profile nests four deep;
    // 40 KB of '[' cost the parser and the position scan seconds and a gigabyte).
    if (text_.size() > kMaxProfileBytes)
      throw UserError(fmt::format("{}: the machine profile has {} bytes, more than the {} KiB a "
                                  "profile may have",
                                  file_, text_.size(), kMaxProfileBytes >> 10));
    {
      int depth = 0;
      bool inString = false;
      Position p;
      for (size_t i = 0; i < text_.size(); ++i) {
        const char c = text_[i];
        if (inString) {
          if (c == '\\') ++i;
          else if (c == '"') inString = false;
        } else if (c == '"') {
          inString = true;
        } else if ((c == '{' || c == '[') && ++depth > kMaxProfileNesting) {
          p = PositionOf(text_, i);
          throw UserError(fmt::format("{}:{}:{}: not a machine profile: nested more than {} deep",
                                      file_, p.line, p.column, kMaxProfileNesting));
        } else if (c == '}' || c == ']') {
          --depth;
        }
      }
    }
    nlohmann::json j;
    try {
      RefuseNulBytes(text_, file_);  // nlohmann would stop reading at it
      j = nlohmann::json::parse(text_);
    } catch (const nlohmann::json::parse_error& e) {
      const Position p = PositionOf(text_, e.byte == 0 ? 0 : e.byte - 1);
      std::string what = e.what();
      if (auto colon = what.find("syntax error"); colon != std::string::npos)
        what = what.substr(colon);
      throw UserError(fmt::format("{}:{}:{}: not valid JSON: {}", file_, p.line, p.column, what));
    } catch (const nlohmann::json::exception& e) {
      // A number too large for a double ("1e999", a megabyte of digits): nlohmann's
      // out_of_range, which carries no position.
      std::string what = e.what();
      if (auto bracket = what.find("] "); bracket != std::string::npos)
        what = what.substr(bracket + 2);
      throw UserError(fmt::format("{}: not valid JSON: {}", file_, what));
    }
    at_ = KeyPositions(text_);
    if (!at_.duplicate.empty()) Throw(at_.duplicateAt, at_.duplicate, "this key appears twice");
    MachineProfile p;
    p.file = file_;
    Keys(j, "", {"name", "description", "source", "entries"});
    p.name = String(j, "name");
    if (p.name.size() > 40 ||
        p.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789._-") != std::string::npos)
      Fail("name", "expected up to 40 characters of a-z, 0-9, '.', '_', '-'");
    p.description = String(j, "description");
    p.source = String(j, "source");
    const nlohmann::json& entries = j["entries"];
    std::vector<std::string> names;
    for (const EntrySpec& e : kGeometry) names.push_back(e.name);
    for (int i = 0; i < kMicroOpCount; ++i) names.push_back(kMicroOpNames[i]);
    Keys(entries, "entries", names);
    auto number = [&](int g, std::string* note) {
      const std::string path = std::string("entries.") + kGeometry[g].name;
      const nlohmann::json& e = Entry(entries, kGeometry[g], note);
      if (!e["value"].is_number())
        Fail(path + ".value", "expected a number, got " + Kind(e["value"]));
      const double v = e["value"].get<double>();
      if (std::string err = RangeError(kGeometry[g].name, v); !err.empty())
        Fail(path + ".value", err + ", got " + NumberText(v));
      return v;
    };
    p.clockHz = number(0, &p.geometryNote[0]);
    p.physicalPes = static_cast<int>(number(1, &p.geometryNote[1]));
    p.internalBitsPerPe = static_cast<int64_t>(number(2, &p.geometryNote[2]));
    p.externalBitsPerPe = static_cast<int64_t>(number(3, &p.geometryNote[3]));
    {
      const nlohmann::json& e = Entry(entries, kGeometry[4], &p.geometryNote[4]);
      const std::string path = "entries.meshShapes.value";
      if (!e["value"].is_array() || e["value"].empty())
        Fail(path, "expected a list of mesh shapes such as [\"64x128\"], got " +
                       (e["value"].is_array() ? std::string("an empty list") : Kind(e["value"])));
      for (size_t k = 0; k < e["value"].size(); ++k) {
        const std::string at = path + "." + std::to_string(k);
        if (!e["value"][k].is_string())
          Fail(at, "expected a shape such as \"64x128\", got " + Kind(e["value"][k]));
        const std::string shape = e["value"][k].get<std::string>();
        MeshShape m{ParseShape(shape)};
        if (m.extent.empty())
          Fail(at, "expected a shape of 1 to 4 positive extents such as \"64x128\", of at most "
                   "2^24 PEs, got \"" +
                       shape + "\"");
        if (static_cast<int64_t>(m.Size()) != p.physicalPes)
          Fail(at, fmt::format("the shape {} has {} PEs, but physicalPes is {}", shape, m.Size(),
                               p.physicalPes));
        p.shapes.push_back(m);
      }
    }
    p.floatSubnormals = number(5, &p.floatNote) != 0;
    for (int i = 0; i < kMicroOpCount; ++i) {
      const EntrySpec spec{kMicroOpNames[i], "cycles"};
      const nlohmann::json& e = Entry(entries, spec, &p.note[i]);
      const std::string path = std::string("entries.") + spec.name + ".value";
      if (!e["value"].is_number()) Fail(path, "expected a number, got " + Kind(e["value"]));
      p.cost[i] = e["value"].get<double>();
      if (std::string err = RangeError(spec.name, p.cost[i]); !err.empty())
        Fail(path, err + ", got " + NumberText(p.cost[i]));
    }
    return p;
  }

 private:
  // At the value of `path` (`atKey`: at its key); a missing key at its parent's value (the
  // nearest path that is in the text).
  [[noreturn]] void Fail(const std::string& path, const std::string& what,
                         bool atKey = false) const {
    if (atKey && at_.key.count(path)) Throw(at_.key.at(path), path, what);
    std::string at = path;
    while (!at.empty() && !at_.value.count(at))
      at = at.rfind('.') == std::string::npos ? "" : at.substr(0, at.rfind('.'));
    Throw(at_.value.count(at) ? at_.value.at(at) : Position{}, path, what);
  }
  [[noreturn]] void Throw(const Position& p, const std::string& path,
                          const std::string& what) const {
    throw UserError(fmt::format("{}:{}:{}: {}: {}", file_, p.line, p.column,
                                path.empty() ? "(top level)" : path, what));
  }
  static std::string Kind(const nlohmann::json& v) {
    return v.is_null() ? "null" : std::string(v.type_name());
  }
  // `j` (at `path`) must be an object with exactly `keys`.
  void Keys(const nlohmann::json& j, const std::string& path,
            const std::vector<std::string>& keys) const {
    if (!j.is_object()) Fail(path, "expected an object, got " + Kind(j));
    auto join = [&](const std::string& k) { return path.empty() ? k : path + "." + k; };
    for (auto it = j.begin(); it != j.end(); ++it)
      if (std::find(keys.begin(), keys.end(), it.key()) == keys.end()) {
        std::string known;
        for (const std::string& k : keys) known += (known.empty() ? "" : ", ") + k;
        Fail(join(it.key()), "unknown key (expected: " + known + ")", true);
      }
    for (const std::string& k : keys)
      if (!j.contains(k)) Fail(join(k), "missing key");
  }
  std::string String(const nlohmann::json& j, const std::string& key,
                     const std::string& path = "") const {
    const std::string at = path.empty() ? key : path + "." + key;
    if (!j[key].is_string()) Fail(at, "expected a string, got " + Kind(j[key]));
    std::string s = j[key].get<std::string>();
    if (s.empty()) Fail(at, "expected a non-empty string");
    return s;
  }
  // One entry: {"value", "unit" (exactly spec.unit), "source"}.
  const nlohmann::json& Entry(const nlohmann::json& entries, const EntrySpec& spec,
                              std::string* source) const {
    const std::string path = std::string("entries.") + spec.name;
    const nlohmann::json& e = entries[spec.name];
    Keys(e, path, {"value", "unit", "source"});
    if (String(e, "unit", path) != spec.unit)
      Fail(path + ".unit",
           fmt::format("expected \"{}\", got \"{}\"", spec.unit, e["unit"].get<std::string>()));
    *source = String(e, "source", path);
    return e;
  }

  const std::string& text_;
  const std::string& file_;
  Positions at_;
};
}  // namespace

MachineProfile ProfileFromJson(const std::string& text, const std::string& file) {
  // A UTF-8 byte-order mark, as some editors write one, is not part of the JSON (nlohmann
  // skips it; the position scan would take it for a value and lose the nesting).
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) return ProfileReader(text.substr(3), file).Read();
  return ProfileReader(text, file).Read();
}

const std::string& BuiltInProfileText(const std::string& name) {
  auto it = BuiltIns().find(name);
  if (it == BuiltIns().end()) {
    std::string known;
    for (auto& [n, t] : BuiltIns()) known += (known.empty() ? "" : ", ") + n;
    throw UserError(fmt::format(
        "unknown machine profile '{}' (built in: {}; or a profile file's path)", name, known));
  }
  return it->second;
}

MachineProfile Profile(const std::string& nameOrFile) {
  if (BuiltIns().count(nameOrFile))
    return ProfileFromJson(BuiltIns().at(nameOrFile),
                           "built-in bitserial/profiles/" + nameOrFile + ".json");
  // Not a built-in name and no file: the name is the likelier mistake unless it looks like a
  // path.
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(nameOrFile, ec)) &&
      nameOrFile.find('/') == std::string::npos && nameOrFile.find(".json") == std::string::npos)
    BuiltInProfileText(nameOrFile);  // throws "unknown machine profile", listing them
  // Only a regular file (fixed/input_file.h): a FIFO would block, a directory is no profile.
  return ProfileFromJson(ReadInputFile(nameOrFile, {"the machine profile file",
                                                    "a machine profile file (JSON)"},
                                       kMaxProfileBytes),
                         nameOrFile);
}

std::vector<std::string> ProfileNames() {
  std::vector<std::string> names;
  for (auto& [n, t] : BuiltIns()) names.push_back(n);
  return names;
}

std::string MachineProfile::FileText() const {
  auto q = [](const std::string& s) { return nlohmann::json(s).dump(); };
  auto entry = [&](const std::string& key, const std::string& value, const char* unit,
                   const std::string& src, bool last) {
    return fmt::format("    {}: {{\"value\": {}, \"unit\": {}, \"source\": {}}}{}\n", q(key), value,
                       q(unit), q(src), last ? "" : ",");
  };
  std::string shapes;
  for (const MeshShape& m : this->shapes) shapes += (shapes.empty() ? "" : ", ") + q(m.Name());
  std::string s = fmt::format(
      "{{\n  \"name\": {},\n  \"description\": {},\n  \"source\": {},\n  \"entries\": {{\n",
      q(name), q(description), q(source));
  const double geometry[] = {clockHz, double(physicalPes), double(internalBitsPerPe),
                             double(externalBitsPerPe)};
  for (int g = 0; g < 4; ++g)
    s += entry(kGeometry[g].name, NumberText(geometry[g]), kGeometry[g].unit, geometryNote[g],
               false);
  s += entry("meshShapes", "[" + shapes + "]", kGeometry[4].unit, geometryNote[4], false);
  s += entry("floatSubnormals", floatSubnormals ? "1" : "0", kGeometry[5].unit, floatNote, false);
  for (int i = 0; i < kMicroOpCount; ++i)
    s += entry(kMicroOpNames[i], NumberText(cost[i]), "cycles", note[i], i + 1 == kMicroOpCount);
  return s + "  }\n}\n";
}

void MachineProfile::Override(const std::string& assignment) {
  auto eq = assignment.find('=');
  if (eq == std::string::npos)
    throw UserError(fmt::format("profile override '{}': expected name=value", assignment));
  std::string key = assignment.substr(0, eq);
  double v = ParseNumber(assignment.substr(eq + 1), "profile override '" + assignment + "'");
  auto check = [&] {
    if (std::string err = RangeError(key, v); !err.empty())
      throw UserError(fmt::format("profile override '{}': {}", assignment, err));
  };
  if (key == "physicalPes" || key == "meshShapes")
    throw UserError(fmt::format(
        "profile override '{}': the geometry ({}) is set in a profile file, with its mesh shapes "
        "(zephyr profile show NAME prints one to edit)",
        assignment, key));
  if (key == "clockHz") {
    check();
    clockHz = v;
    geometryNote[0] = "overridden at run time";
    return;
  }
  if (key == "internalBitsPerPe" || key == "externalBitsPerPe") {
    check();
    const bool internal = key == "internalBitsPerPe";
    (internal ? internalBitsPerPe : externalBitsPerPe) = static_cast<int64_t>(v);
    geometryNote[internal ? 2 : 3] = "overridden at run time";
    return;
  }
  if (key == "floatSubnormals") {
    check();
    floatSubnormals = v != 0;
    floatNote = "overridden at run time";
    return;
  }
  for (int i = 0; i < kMicroOpCount; ++i)
    if (key == kMicroOpNames[i]) {
      check();
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
