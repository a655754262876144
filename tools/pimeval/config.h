// tools/pimeval/config.h — PIMeval's device files read for the PIMeval API (docs/pim.md): the
// .cfg device description and the .ini memory file its memory_config_file names, and the
// machine profile a device runs on.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "bitserial/profile.h"

namespace zephyr::pimeval {

// A device's geometry: ranks x banks per rank x subarrays per bank subarrays, each of `cols`
// one-bit PEs (columns) with `rows` bits of memory each (PIMeval's terms, libpimeval.h).
struct Geometry {
  unsigned ranks = 0, banks = 0, subarrays = 0, rows = 0, cols = 0;
  uint64_t Pes() const { return uint64_t{ranks} * banks * subarrays * cols; }
  uint64_t Cores() const { return uint64_t{ranks} * banks * subarrays; }
};

// A parsed .cfg file. Keys absent from the file keep the values given here (0 / empty).
struct DeviceConfig {
  Geometry geometry;
  std::string simulationTarget;  // "PIM_DEVICE_BITSIMD_V", ... as written; empty if absent
  std::string memoryFile;        // the memory_config_file value, resolved beside the .cfg
  unsigned maxThreads = 0, bufferSize = 0;
};

// Reads PIMeval's .cfg text: lines "key = value", anything after ';' a comment, blank lines
// skipped. UserError "FILE:LINE: what" for a line without '=', an empty or unknown key, a
// number that is not a whole number in [1, 2^32), a repeated key; "FILE: ..." for a missing
// geometry key. `file` names the file in errors and resolves the memory file's directory.
DeviceConfig ParseDeviceConfig(const std::string& text, const std::string& file);
// The file at `path` (a regular file of at most 1 MiB: fixed/input_file.h), then as above.
DeviceConfig ReadDeviceConfig(const std::string& path);

// A memory .ini file (DRAMsim3's format, PIMeval's configs/): "[section]" lines and
// "key = value" lines; UserError "FILE:LINE: what" for any other line and for a key given twice
// (PIMeval's shipped files repeat none, in any section).
std::map<std::string, std::string> ParseMemoryIni(const std::string& text, const std::string& file);
std::map<std::string, std::string> ReadMemoryIni(const std::string& path);  // as ReadDeviceConfig

// The BitSIMD-V profile's timings from a memory file, with the derivation of docs/present-day.md
// and bitserial/profiles/pim-bitsimd-v-bank.json: clockHz = 1/tCK; a row read or write (and
// the multiply accumulator's) = tRAS + tRP cycles; aluStep = meshHop = 3 tCCD_S (a full-adder
// step, a shift through bit registers); flagOp = activitySet = broadcastBit = tCCD_S;
// reduceBit = cols/64 x 0.76 ns in tCK (PIMeval pimPerfEnergyBitSerial.h:37); hostPlane keeps
// the profile's bytes per second (its DDR4 channel). UserError naming the file and the first
// parameter of tCK, tRAS, tRP, tCCD_S it lacks or cannot read as a decimal number in range:
// tCK in [0.001, 10^9] ns (1 THz down to the profile reader's 1 Hz), the others in [1, 10^8]
// cycles.
void ApplyMemoryTimings(bitserial::MachineProfile& profile,
                        const std::map<std::string, std::string>& ini, const std::string& file,
                        unsigned cols);

}  // namespace zephyr::pimeval
