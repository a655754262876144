// PIMeval's device files (tools/pimeval/config.h): the .cfg reader's located errors, the memory
// file's timings with the BitSIMD-V derivation, and every config PIMeval ships (when
// ../shared/pimbench is there) either read or refused naming why.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include "bitserial/profile.h"
#include "fixed/check.h"
#include "tools/pimeval/config.h"
#include "tools/pimeval/libpimeval.h"

namespace zephyr::pimeval {
namespace {

namespace fs = std::filesystem;
using bitserial::MicroOp;

const char* kGood =
    "num_ranks = 2\n"
    "num_bank_per_rank = 128 ; a comment\n"
    "\n"
    "num_subarray_per_bank = 32\n"
    "num_row_per_subarray = 1024\n"
    "num_col_per_subarray = 8192\n"
    "simulation_target = PIM_DEVICE_BITSIMD_V\n"
    "max_num_threads = 4; Maximum Number of Threads\n"
    "memory_config_file = HBM2_8Gb_x128.ini";  // no newline at the end, as PIMeval's files

TEST(PimConfig, ReadsPimevalsCfgFormat) {
  const DeviceConfig c = ParseDeviceConfig(kGood, "dir/a.cfg");
  EXPECT_EQ(c.geometry.ranks, 2u);
  EXPECT_EQ(c.geometry.banks, 128u);
  EXPECT_EQ(c.geometry.subarrays, 32u);
  EXPECT_EQ(c.geometry.rows, 1024u);
  EXPECT_EQ(c.geometry.cols, 8192u);
  EXPECT_EQ(c.simulationTarget, "PIM_DEVICE_BITSIMD_V");
  EXPECT_EQ(c.maxThreads, 4u);
  EXPECT_EQ(c.memoryFile, "dir/HBM2_8Gb_x128.ini");  // beside the .cfg
}

void ExpectError(const std::string& text, const std::string& want) {
  try {
    ParseDeviceConfig(text, "x.cfg");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(PimConfig, MalformedLinesAreErrorsWithFileAndLine) {
  ExpectError("num_ranks = 1\nnum_bank_per_rank 4\n", "x.cfg:2: expected 'key = value'");
  ExpectError("num_ranks = one\n", "x.cfg:1: num_ranks must be a whole number");
  ExpectError("num_ranks = 0\n", "x.cfg:1: num_ranks must be a whole number");
  ExpectError("num_ranks = -3\n", "x.cfg:1: num_ranks must be a whole number");
  ExpectError("\n\n = 4\n", "x.cfg:3: a key is missing");
  ExpectError("num_ranks = 1\nnum_ranks = 2\n", "x.cfg:2: num_ranks is given twice (first at line 1)");
  ExpectError("num_rank = 1\n", "x.cfg:1: unknown key 'num_rank'");
  ExpectError("num_ranks = 1\n", "x.cfg: num_bank_per_rank is missing");
}

TEST(PimConfig, ApiErrorsNameTheFile) {
  ::unsetenv("ZEPHYR_MACHINE");
  const fs::path cfg = fs::temp_directory_path() / "zephyr_pim_bad.cfg";
  {
    std::FILE* f = std::fopen(cfg.c_str(), "w");
    std::fputs("num_ranks = 1\nnum_bank_per_rank = x\n", f);
    std::fclose(f);
  }
  testing::internal::CaptureStderr();
  EXPECT_EQ(pimCreateDeviceFromConfig(PIM_FUNCTIONAL, cfg.c_str()), PIM_ERROR);
  EXPECT_EQ(pimCreateDeviceFromConfig(PIM_FUNCTIONAL, "/nonexistent/a.cfg"), PIM_ERROR);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(cfg.string() + ":2: num_bank_per_rank"), std::string::npos) << err;
  EXPECT_NE(err.find("/nonexistent/a.cfg: cannot open the device config file (no such file)"),
            std::string::npos)
      << err;
  fs::remove(cfg);
}

TEST(PimConfig, MemoryFileSetsTheBitSimdTimings) {
  const std::string ini =
      "[dram_structure]\nprotocol = DDR4\n\n[timing]\ntCK = 0.625\ntRP = 22\ntRAS = 52\n"
      "tCCD_S = 4\n";
  bitserial::MachineProfile p = bitserial::Profile("pim-bitsimd-v-bank");
  const bitserial::MachineProfile before = p;
  ApplyMemoryTimings(p, ParseMemoryIni(ini, "m.ini"), "m.ini", 8192);
  // The DDR4-3200 values the built-in profile was derived from come out the same.
  for (MicroOp op : {MicroOp::kReadInternal, MicroOp::kWriteInternal, MicroOp::kAluStep,
                     MicroOp::kFlagOp, MicroOp::kMeshHop, MicroOp::kBroadcastBit,
                     MicroOp::kAccumulatorRead})
    EXPECT_DOUBLE_EQ(p.Cost(op), before.Cost(op)) << bitserial::MicroOpName(op);
  EXPECT_DOUBLE_EQ(p.clockHz, 1.6e9);
  EXPECT_NEAR(p.Cost(MicroOp::kReduceBit), before.Cost(MicroOp::kReduceBit), 0.5);
  EXPECT_NEAR(p.Cost(MicroOp::kHostPlane), before.Cost(MicroOp::kHostPlane), 1e-6);
  EXPECT_NE(p.note[int(MicroOp::kAluStep)].find("m.ini"), std::string::npos);
  // HBM2: tRAS + tRP = 47 cycles at 1 GHz.
  ApplyMemoryTimings(p, ParseMemoryIni("tCK = 1\ntRP = 14\ntRAS = 33\ntCCD_S = 2\n", "h.ini"),
                     "h.ini", 8192);
  EXPECT_DOUBLE_EQ(p.Cost(MicroOp::kReadInternal), 47);
  EXPECT_DOUBLE_EQ(p.Cost(MicroOp::kAluStep), 6);
  EXPECT_DOUBLE_EQ(p.clockHz, 1e9);
}

TEST(PimConfig, MemoryFileLackingATimingIsRefusedNamingIt) {
  bitserial::MachineProfile p = bitserial::Profile("pim-bitsimd-v-bank");
  try {
    ApplyMemoryTimings(p, ParseMemoryIni("tCK = 1\ntRP = 14\ntRAS = 33\n", "h.ini"), "h.ini", 8192);
    ADD_FAILURE();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("h.ini: the memory file has no tCCD_S"), std::string::npos)
        << e.what();
  }
  try {
    ParseMemoryIni("[timing]\ntCK 1\n", "h.ini");
    ADD_FAILURE();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("h.ini:2:"), std::string::npos) << e.what();
  }
}

// The readers take what a user can hand them (issue 39): only regular files, a memory key once,
// and timings that are decimal numbers of a clock the profile can hold.
TEST(PimConfig, FilesThatAreNotRegularOrTimingsOutOfRangeAreRefused) {
  const fs::path dir = fs::temp_directory_path() / "zephyr_pim_kinds";
  fs::create_directories(dir);
  const fs::path fifo = dir / "fifo.cfg";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, want] :
       {std::pair<std::string, std::string>{dir.string(), ": is a directory"},
        {fifo.string(), ": is not a regular file"}}) {
    try {
      ReadDeviceConfig(path);
      ADD_FAILURE() << path;
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(path + want), std::string::npos) << e.what();
    }
    try {
      ReadMemoryIni(path);
      ADD_FAILURE() << path;
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(path + want), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
  try {
    ParseMemoryIni("[timing]\ntCK = 1\n[other]\ntCK = 2\n", "h.ini");
    ADD_FAILURE();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("h.ini:4: tCK is given twice (first at line 2)"),
              std::string::npos)
        << e.what();
  }
  const std::string rest = "tRP = 14\ntRAS = 33\ntCCD_S = 2\n";
  for (const char* tck : {"0x10", "inf", "nan", "1e-300", "1e300", "0", "-1", " ", "1.0.0"}) {
    bitserial::MachineProfile p = bitserial::Profile("pim-bitsimd-v-bank");
    try {
      ApplyMemoryTimings(p, ParseMemoryIni(std::string("tCK = ") + tck + "\n" + rest, "h.ini"),
                         "h.ini", 8192);
      ADD_FAILURE() << tck;
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find("h.ini: tCK must be a decimal number in [0.001, "
                                           "1000000000] ns"),
                std::string::npos)
          << e.what();
    }
  }
  bitserial::MachineProfile p = bitserial::Profile("pim-bitsimd-v-bank");
  try {
    ApplyMemoryTimings(p, ParseMemoryIni("tCK = 1\ntRP = 1e12\ntRAS = 33\ntCCD_S = 2\n", "h.ini"),
                       "h.ini", 8192);
    ADD_FAILURE();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("h.ini: tRP must be a decimal number in [1, "
                                         "100000000] cycles, got '1e12'"),
              std::string::npos)
        << e.what();
  }
}

// PIMeval's own configs (../shared/pimbench/configs): the bit-serial ones create a device with
// their memory file's timings; the bit-parallel ones are refused naming the device.
TEST(PimConfig, PimevalsShippedConfigsAreReadOrRefusedByName) {
  fs::path dir;
  for (fs::path p = fs::current_path(); !p.empty() && p != p.root_path(); p = p.parent_path())
    if (fs::exists(p / "Makefile") && fs::exists(p / ".." / "shared" / "pimbench" / "configs")) {
      dir = p / ".." / "shared" / "pimbench" / "configs";
      break;
    }
  if (dir.empty()) GTEST_SKIP() << "../shared/pimbench/configs is not there";
  ::unsetenv("ZEPHYR_MACHINE");
  int bitSerial = 0, refused = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.path().extension() != ".cfg") continue;
    SCOPED_TRACE(e.path().string());
    const DeviceConfig c = ReadDeviceConfig(e.path().string());
    testing::internal::CaptureStderr();
    const PimStatus s = pimCreateDeviceFromConfig(PIM_FUNCTIONAL, e.path().c_str());
    const std::string err = testing::internal::GetCapturedStderr();
    if (c.simulationTarget.find("BITSIMD_V") != std::string::npos) {
      EXPECT_EQ(s, PIM_OK) << err;
      PimDeviceProperties p;
      EXPECT_EQ(pimGetDeviceProperties(&p), PIM_OK);
      EXPECT_EQ(p.numColPerSubarray, c.geometry.cols);
      EXPECT_EQ(pimDeleteDevice(), PIM_OK);
      ++bitSerial;
    } else {
      EXPECT_EQ(s, PIM_ERROR);
      EXPECT_NE(err.find(c.simulationTarget + " is bit-parallel"), std::string::npos) << err;
      ++refused;
    }
  }
  EXPECT_GT(bitSerial, 0);
  EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace zephyr::pimeval
