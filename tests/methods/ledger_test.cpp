// The fidelity ledger (hosts/methods/ledger.h; docs/validation.md): the machine rows come from
// the engine's cycles, a check's margin is the worst pair's, and no row's error is worse than
// tools/validation_recorded.csv (the quick version of `make validate` in `make test`: the
// machine rows recomputed, the paper rows on the committed sweep).
#include "hosts/methods/ledger.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fixed/check.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr::methods {
namespace {

std::filesystem::path Repo() {  // the nearest directory above the test binary with tools/
  auto dir = std::filesystem::read_symlink("/proc/self/exe").parent_path();
  while (!dir.empty() && dir != dir.root_path() &&
         !std::filesystem::exists(dir / "tools/validation_recorded.csv"))
    dir = dir.parent_path();
  return dir;
}

const LedgerRow& Row(const std::vector<LedgerRow>& rows, const std::string& op) {
  for (const LedgerRow& r : rows)
    if (r.operation == op) return r;
  ADD_FAILURE() << "no row " << op;
  static LedgerRow none;
  return none;
}

// Batcher's MPP rows from the engine's 3n+1 and n²+3n schedules and the float schedules
// (flush to zero, the profile's format): rate = 16384 PEs × 10 MHz ÷ cycles.
TEST(FidelityLedger, MachineRowsAreTheEnginesCycles) {
  const std::vector<LedgerRow> rows = MachineRows();
  const double pes = 16384, clock = 10e6;
  EXPECT_DOUBLE_EQ(Row(rows, "add 8-bit").model, pes * clock / 25 / 1e6);
  EXPECT_DOUBLE_EQ(Row(rows, "add 12-bit").model, pes * clock / 37 / 1e6);
  EXPECT_DOUBLE_EQ(Row(rows, "multiply 8-bit").model, pes * clock / 88 / 1e6);
  EXPECT_DOUBLE_EQ(Row(rows, "multiply 12-bit").model, pes * clock / 180 / 1e6);
  EXPECT_DOUBLE_EQ(Row(rows, "floating add 32-bit").model, pes * clock / 380 / 1e6);
  EXPECT_DOUBLE_EQ(Row(rows, "floating multiply 32-bit").model, pes * clock / 818 / 1e6);
  const LedgerRow& mul = Row(rows, "floating multiply 32-bit");
  EXPECT_DOUBLE_EQ(mul.errorPct, (mul.model - 216) / 216 * 100);
  // BLITZEN at 20 MHz: the 32-bit add (97 cycles) meets its bound; the IEEE multiply on the
  // MPP's schedule (898 cycles with gradual underflow) does not, short by the difference.
  const LedgerRow& add = Row(rows, "add 32-bit (above)");
  EXPECT_DOUBLE_EQ(add.model, pes * 20e6 / 97 / 1e6);
  EXPECT_TRUE(add.holds);
  EXPECT_EQ(add.errorPct, 0);
  const LedgerRow& fmul = Row(rows, "IEEE single multiply (above)");
  EXPECT_DOUBLE_EQ(fmul.model, pes * 20e6 / 898 / 1e6);
  EXPECT_FALSE(fmul.holds);
  EXPECT_DOUBLE_EQ(fmul.errorPct, (450 - fmul.model) / 450 * 100);
}

// A check is the worst pair's margin: on a made-up sweep where SIMD/sequential is slower than
// sequential at one count, Fig 5 does not hold, short by exactly that pair's margin.
TEST(FidelityLedger, ACheckIsItsWorstPair) {
  std::vector<SweepRun> runs = {{"seq", 8, 0, 0, 0, 10},
                                {"simd", 8, 0, 0, 0, 6},
                                {"seq", 16, 0, 0, 0, 20},
                                {"simd", 16, 0, 0, 0, 25}};
  const std::vector<LedgerRow> rows = PaperRows(runs);
  ASSERT_EQ(rows.size(), 1u);  // only Fig 5 has its points
  EXPECT_FALSE(rows[0].holds);
  EXPECT_DOUBLE_EQ(rows[0].model, (20.0 - 25) / 20 * 100);
  EXPECT_DOUBLE_EQ(rows[0].errorPct, 25);
  runs[3].modelSeconds = 15;
  const LedgerRow fixed = PaperRows(runs)[0];
  EXPECT_TRUE(fixed.holds);
  EXPECT_DOUBLE_EQ(fixed.model, 25);  // 16 objects: (20 − 15) ÷ 20
  EXPECT_EQ(fixed.errorPct, 0);
}

TEST(FidelityLedger, AMalformedSweepIsRefusedAtItsLine) {
  testing::TempDir dir;
  const std::string file = dir / "runs.csv";
  std::ofstream(file) << "method,objects,children,frame,ethernet_bps,model_s,bytes,pixels\n"
                      << "seq,8,0,0,0,1.5,0,100\nsimd,8,0,0,0,fast,0,100\n";
  try {
    ReadRuns(file);
    FAIL() << "accepted";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find(file + ":3: 'fast' is not a number"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ReadRuns(dir / "none.csv"), UserError);
}

// The quick ledger: every row recomputed (paper rows on the committed sweep) is no worse than
// its record; and a record made stricter than the model is caught.
TEST(FidelityLedger, NoRowIsWorseThanItsRecord) {
  const auto repo = Repo();
  const std::string runs = (repo / "docs/results/testbed-ufmg1992/runs.csv").string();
  const std::string recorded = (repo / "tools/validation_recorded.csv").string();
  const auto ok = testing::RunZephyrProcess("validate --runs " + runs + " --check " + recorded);
  EXPECT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("14 rows checked"), std::string::npos) << ok.output;
  testing::TempDir dir;
  std::ifstream in(recorded);
  std::ofstream strict(dir / "strict.csv");
  for (std::string line; std::getline(in, line);)
    strict << (line.rfind("mpp,floating multiply 32-bit,", 0) == 0
                   ? "mpp,floating multiply 32-bit,-1.0"
                   : line)
           << "\n";
  strict.close();
  const auto bad =
      testing::RunZephyrProcess("validate --runs " + runs + " --check " + (dir / "strict.csv"));
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("floating multiply 32-bit: error -7.27"), std::string::npos)
      << bad.output;
}

}  // namespace
}  // namespace zephyr::methods
