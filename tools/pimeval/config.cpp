// tools/pimeval/config.cpp — PIMeval's .cfg and .ini files (config.h).
#include "tools/pimeval/config.h"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "fixed/check.h"
#include "fixed/input_file.h"

namespace zephyr::pimeval {

namespace {

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// PIMeval's shipped files are a few KiB; anything past 1 MiB is not one of them.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 20;

unsigned ParseCount(const std::string& value, const std::string& where, const std::string& key) {
  size_t used = 0;
  unsigned long long v = 0;
  bool ok = !value.empty() && value.find_first_not_of("0123456789") == std::string::npos;
  if (ok) {
    try {
      v = std::stoull(value, &used);
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok || used != value.size() || v < 1 || v > 0xffffffffull)
    throw UserError(fmt::format("{}: {} must be a whole number in [1, 4294967295], got '{}'",
                                where, key, value));
  return static_cast<unsigned>(v);
}

}  // namespace

DeviceConfig ParseDeviceConfig(const std::string& text, const std::string& file) {
  DeviceConfig c;
  std::map<std::string, int> seen;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string where = fmt::format("{}:{}", file, line);
    std::string s = raw.substr(0, raw.find(';'));
    s = Trim(s);
    if (s.empty()) continue;
    const size_t eq = s.find('=');
    if (eq == std::string::npos)
      throw UserError(fmt::format("{}: expected 'key = value', got '{}'", where, Trim(raw)));
    const std::string key = Trim(s.substr(0, eq)), value = Trim(s.substr(eq + 1));
    if (key.empty()) throw UserError(fmt::format("{}: a key is missing before '='", where));
    if (seen.count(key))
      throw UserError(fmt::format("{}: {} is given twice (first at line {})", where, key, seen[key]));
    seen[key] = line;
    if (key == "num_ranks") c.geometry.ranks = ParseCount(value, where, key);
    else if (key == "num_bank_per_rank") c.geometry.banks = ParseCount(value, where, key);
    else if (key == "num_subarray_per_bank") c.geometry.subarrays = ParseCount(value, where, key);
    else if (key == "num_row_per_subarray") c.geometry.rows = ParseCount(value, where, key);
    else if (key == "num_col_per_subarray") c.geometry.cols = ParseCount(value, where, key);
    else if (key == "max_num_threads") c.maxThreads = ParseCount(value, where, key);
    else if (key == "buffer_size") {
      if (value != "0") c.bufferSize = ParseCount(value, where, key);
    } else if (key == "simulation_target") {
      if (value.empty()) throw UserError(fmt::format("{}: simulation_target is empty", where));
      c.simulationTarget = value;
    } else if (key == "memory_config_file") {
      if (value.empty()) throw UserError(fmt::format("{}: memory_config_file is empty", where));
      const size_t slash = file.find_last_of('/');
      c.memoryFile = value[0] == '/' || slash == std::string::npos
                         ? value
                         : file.substr(0, slash + 1) + value;
    } else {
      throw UserError(fmt::format(
          "{}: unknown key '{}' (known: num_ranks, num_bank_per_rank, num_subarray_per_bank, "
          "num_row_per_subarray, num_col_per_subarray, simulation_target, memory_config_file, "
          "max_num_threads, buffer_size)",
          where, key));
    }
  }
  for (const char* k : {"num_ranks", "num_bank_per_rank", "num_subarray_per_bank",
                        "num_row_per_subarray", "num_col_per_subarray"})
    if (!seen.count(k)) throw UserError(fmt::format("{}: {} is missing", file, k));
  return c;
}

DeviceConfig ReadDeviceConfig(const std::string& path) {
  return ParseDeviceConfig(
      ReadInputFile(path, {"the device config file", "a PIMeval device config file"},
                    kMaxFileBytes),
      path);
}

std::map<std::string, std::string> ReadMemoryIni(const std::string& path) {
  return ParseMemoryIni(
      ReadInputFile(path, {"the memory file", "a DRAM memory .ini file"}, kMaxFileBytes), path);
}

std::map<std::string, std::string> ParseMemoryIni(const std::string& text,
                                                  const std::string& file) {
  std::map<std::string, std::string> kv;
  std::map<std::string, int> seen;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    std::string s = Trim(raw.substr(0, raw.find_first_of(";#")));
    if (s.empty() || (s.front() == '[' && s.back() == ']')) continue;
    const size_t eq = s.find('=');
    if (eq == std::string::npos || Trim(s.substr(0, eq)).empty())
      throw UserError(
          fmt::format("{}:{}: expected '[section]' or 'key = value', got '{}'", file, line, s));
    const std::string key = Trim(s.substr(0, eq));
    if (!seen.emplace(key, line).second)
      throw UserError(fmt::format("{}:{}: {} is given twice (first at line {})", file, line, key,
                                  seen[key]));
    kv[key] = Trim(s.substr(eq + 1));
  }
  return kv;
}

void ApplyMemoryTimings(bitserial::MachineProfile& p,
                        const std::map<std::string, std::string>& ini, const std::string& file,
                        unsigned cols) {
  // tCK in ns: from 1 ps (a 1 THz clock) to 1 s (the profile reader's 1 Hz floor); the others in
  // cycles of tCK, at most 10^8 (so that tRAS + tRP and 3 tCCD_S stay within the 10^9 cycles
  // a profile cost may have).
  auto get = [&](const char* key, double minimum, double maximum, const char* unit) {
    auto it = ini.find(key);
    if (it == ini.end())
      throw UserError(fmt::format(
          "{}: the memory file has no {} (the BitSIMD-V timings need tCK, tRAS, tRP and tCCD_S; "
          "docs/pim.md)",
          file, key));
    // A decimal number (no hex, inf or nan, which stod would take), then its range.
    const std::string& text = it->second;
    const bool decimal = !text.empty() &&
                         text.find_first_not_of("0123456789.eE+-") == std::string::npos;
    try {
      size_t used = 0;
      const double v = decimal ? std::stod(text, &used) : 0;
      if (decimal && used == text.size() && v >= minimum && v <= maximum) return v;
    } catch (const std::exception&) {
    }
    throw UserError(fmt::format("{}: {} must be a decimal number in [{}, {}] {}, got '{}'",
                                file, key, minimum, maximum, unit, text));
  };
  const double tCK = get("tCK", 1e-3, 1e9, "ns"), tRAS = get("tRAS", 1, 1e8, "cycles"),
               tRP = get("tRP", 1, 1e8, "cycles"), tCCD = get("tCCD_S", 1, 1e8, "cycles");
  using bitserial::MicroOp;
  const double bytesPerSecond =
      p.physicalPes / 8.0 / p.Cost(MicroOp::kHostPlane) * p.clockHz;  // the profile's channel
  const std::string src = fmt::format("from {} (tCK {} ns, tRAS {}, tRP {}, tCCD_S {}; docs/pim.md)",
                                      file, tCK, tRAS, tRP, tCCD);
  auto set = [&](MicroOp op, double cycles, const std::string& how) {
    p.cost[static_cast<int>(op)] = cycles;
    p.note[static_cast<int>(op)] = how + " " + src;
  };
  p.clockHz = 1e9 / tCK;
  p.geometryNote[0] = "1/tCK " + src;
  for (MicroOp op : {MicroOp::kReadInternal, MicroOp::kWriteInternal, MicroOp::kReadExternal,
                     MicroOp::kWriteExternal, MicroOp::kAccumulatorRead,
                     MicroOp::kAccumulatorWrite})
    set(op, tRAS + tRP, "a row access, tRAS + tRP,");
  set(MicroOp::kAluStep, 3 * tCCD, "a full-adder step, 3 tCCD_S,");
  set(MicroOp::kMeshHop, 3 * tCCD, "a shift through the bit registers, 3 tCCD_S,");
  for (MicroOp op : {MicroOp::kFlagOp, MicroOp::kActivitySet, MicroOp::kBroadcastBit})
    set(op, tCCD, "one bit-register op, tCCD_S,");
  set(MicroOp::kReduceBit, cols / 64.0 * 0.76 / tCK,
      "a row popcount, cols/64 x 0.76 ns (PIMeval pimPerfEnergyBitSerial.h:37),");
  set(MicroOp::kHostPlane, p.physicalPes / 8.0 / bytesPerSecond * p.clockHz,
      "the profile's channel bandwidth at the new clock,");
}

}  // namespace zephyr::pimeval
