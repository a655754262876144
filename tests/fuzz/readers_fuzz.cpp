// libFuzzer target for every reader of a user's file besides the NFF scene (issue 39): the
// machine profile reader and `--set` (bitserial/profile.h), the ledger's runs.csv and recorded
// errors (hosts/ledger/ledger.h: `zephyr validate --runs` / `--check`), and the calibrate
// report (`zephyr testbed calibrate`: JSON, then hosts/testbed/testbed.h), and PIMeval's device
// files as the PIMeval API reads them (tools/pimeval/config.h: a .cfg, and a memory .ini with
// the BitSIMD-V timings taken from it). The first byte picks the reader (modulo 6: the seeds'
// ASCII '0'-'5'), the rest is the file. Any input must read or raise a UserError — never a crash,
// an internal-check abort, an uncaught exception, a hang or a sanitizer report. Built by
// `make fuzz` with clang, -fsanitize=fuzzer,address,undefined; seeds in
// tests/fuzz/readers_corpus/ and made from the built-in profiles.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>

#include "bitserial/profile.h"
#include "fixed/check.h"
#include "hosts/ledger/ledger.h"
#include "hosts/testbed/testbed.h"
#include "tools/pimeval/config.h"

namespace {

// A file in a scratch directory made once (the CSV readers take a path).
std::string ScratchFile(std::string_view text) {
  static const std::filesystem::path dir = [] {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "zephyr-readers-fuzz-XXXXXX").string();
    const std::filesystem::path d = ::mkdtemp(pattern.data());
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    });
    return d;
  }();
  const std::string path = (dir / "input.csv").string();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(text.data(), text.size());
  return path;
}

void Profile(std::string_view text) {
  // The file, then each of its last lines as a --set override of what it read.
  zephyr::bitserial::MachineProfile p;
  try {
    p = zephyr::bitserial::ProfileFromJson(std::string(text), "fuzz.json");
  } catch (const zephyr::UserError&) {
    p = zephyr::bitserial::Profile("wavetracer");
  }
  std::istringstream lines{std::string(text.substr(0, 4096))};
  int n = 0;
  for (std::string line; std::getline(lines, line) && n < 8; ++n) {
    try {
      p.Override(line);
    } catch (const zephyr::UserError&) {
    }
  }
  // What it read must write out and read back to itself.
  if (zephyr::bitserial::ProfileFromJson(p.FileText(), "again.json").FileText() != p.FileText())
    __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0 || size > (1 << 16)) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (data[0] % 6) {
      case 0:
        Profile(text);
        break;
      case 1:
        zephyr::ledger::ReadRuns(ScratchFile(text));
        break;
      case 2:
        zephyr::ledger::ReadRecorded(ScratchFile(text));
        break;
      case 3: {
        const nlohmann::json r = nlohmann::json::parse(text, nullptr, false);
        if (!r.is_discarded()) zephyr::testbed::CalibrateThisHost(r, "fuzz.json");
        break;
      }
      case 4: {
        // A device read must have its whole geometry, each count at least 1.
        const zephyr::pimeval::DeviceConfig c =
            zephyr::pimeval::ReadDeviceConfig(ScratchFile(text));
        if (c.geometry.Pes() == 0) __builtin_trap();
        break;
      }
      case 5: {
        // Timings taken must leave a clock and costs the profile can write and read back.
        zephyr::bitserial::MachineProfile p = zephyr::bitserial::Profile("pim-bitsimd-v-bank");
        zephyr::pimeval::ApplyMemoryTimings(
            p, zephyr::pimeval::ReadMemoryIni(ScratchFile(text)), "fuzz.ini", 8192);
        try {
          zephyr::bitserial::ProfileFromJson(p.FileText(), "timed.json");
        } catch (const zephyr::UserError&) {
          __builtin_trap();
        }
        break;
      }
    }
  } catch (const zephyr::UserError&) {
  }
  return 0;
}
