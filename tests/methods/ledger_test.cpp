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
    EXPECT_NE(std::string(e.what()).find(file + ":3: model_s 'fast' is not a finite number"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ReadRuns(dir / "none.csv"), UserError);
}

// Every other kind of malformed sweep (issue 39): a short row aborted; nan, inf, empty,
// negative and all-zero times and a header-only file passed as findings that hold.
TEST(FidelityLedger, EveryKindOfMalformedSweepIsRefused) {
  testing::TempDir dir;
  const std::string header = "method,objects,children,frame,ethernet_bps,model_s,bytes,pixels\n";
  const std::string good = "seq,8,0,0,0,1.5,0,100\n";
  struct Case {
    std::string row, want;
  };
  const std::vector<Case> cases = {
      {"simd,8,0,0\n", ":3: 4 columns, the header has 8"},
      {"simd,8,0,0,0,nan,0,100\n", ":3: model_s 'nan' is not a finite number"},
      {"simd,8,0,0,0,inf,0,100\n", ":3: model_s 'inf' is not a finite number"},
      {"simd,8,0,0,0,,0,100\n", ":3: model_s '' is not a finite number"},
      {"simd,8,0,0,0,-2,0,100\n", ":3: model_s -2 is out of range (expected above 0)"},
      {"simd,8,0,0,0,0,0,100\n", ":3: model_s 0 is out of range (expected above 0)"},
      {"simd,8.5,0,0,0,1,0,100\n", ":3: objects 8.5 is out of range (expected a whole number from 1)"},
      {"simd,8,-1,0,0,1,0,100\n", ":3: children -1 is out of range"},
      {"simd,8,0,0,0,1,-5,100\n", ":3: bytes -5 is out of range"},
  };
  for (const Case& c : cases) {
    const std::string file = dir / "runs.csv";
    std::ofstream(file) << header << good << c.row;
    try {
      ReadRuns(file);
      ADD_FAILURE() << "accepted: " << c.row;
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(file + c.want), std::string::npos)
          << c.row << " -> " << e.what();
    }
  }
  const std::string only = dir / "header.csv";
  std::ofstream(only) << header;
  EXPECT_THROW(ReadRuns(only), UserError);
  const std::string folder = std::filesystem::path(only).parent_path().string();
  try {
    ReadRuns(folder);
    ADD_FAILURE() << "a directory was read";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
}

// `zephyr validate --check`: a record that cannot be read is refused whole (a non-number or
// empty error aborted; an empty, header-only, nan or directory file passed with "0 worse"),
// and no output may overwrite an input of the run.
TEST(FidelityLedger, AMalformedRecordIsRefusedAndNoInputIsOverwritten) {
  testing::TempDir dir;
  const std::string recorded = (Repo() / "tools/validation_recorded.csv").string();
  const std::string h = "machine,operation,error_pct\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {h + "mpp,add 8-bit,abc\n", ":2: error_pct 'abc' is not a finite number"},
      {h + "mpp,add 8-bit,\n", ":2: error_pct '' is not a finite number"},
      {h + "mpp,add 8-bit,nan\n", ":2: error_pct 'nan' is not a finite number"},
      {h + "mpp\n", ":2: expected machine,operation,error_pct"},
      {h, ": holds no recorded rows"},
      {"", ":1: expected the header machine,operation,error_pct"},
  };
  for (const auto& [text, want] : cases) {
    const std::string file = dir / "rec.csv";
    std::ofstream(file) << text;
    const auto r = testing::RunZephyrProcess("validate --check " + file);
    EXPECT_NE(r.status, 0) << text;
    EXPECT_NE(r.output.find(file + want), std::string::npos) << text << "\n" << r.output;
  }
  const auto folder = testing::RunZephyrProcess("validate --check " + std::filesystem::path(dir / "x").parent_path().string());
  EXPECT_NE(folder.status, 0);
  EXPECT_NE(folder.output.find("is a directory"), std::string::npos) << folder.output;
  // --csv naming the --check file, --out naming --runs: refused before anything is written.
  const std::string copy = dir / "copy.csv";
  std::filesystem::copy_file(recorded, copy);
  const std::string before = [&] {
    std::ifstream in(copy);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  auto r = testing::RunZephyrProcess("validate --check " + copy + " --csv " + copy);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--csv"), std::string::npos) << r.output;
  std::ifstream in(copy);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), before);
  const std::string runs = dir / "runs.csv";
  std::filesystem::copy_file(Repo() / "docs/results/testbed-ufmg1992/runs.csv", runs);
  r = testing::RunZephyrProcess("validate --runs " + runs + " --out " + runs);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
  EXPECT_EQ(std::filesystem::file_size(runs),
            std::filesystem::file_size(Repo() / "docs/results/testbed-ufmg1992/runs.csv"));
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
