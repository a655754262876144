// The fidelity ledger (hosts/ledger/ledger.h; docs/validation.md): the machine rows come from
// the engine's cycles, a check's margin is the worst pair's, and no row's error is worse than
// tools/validation_recorded.csv (the quick version of `make validate` in `make test`: the
// machine rows recomputed, the paper rows on the committed sweep).
#include "hosts/ledger/ledger.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fixed/check.h"
#include "hosts/testbed/host_profile.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr::ledger {
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

// The summary per machine: rows, the rows with an error (rate, time, model) and their mean and
// largest absolute error over those rows only, and the bounds or checks held; a machine with
// both kinds of row averages its errors over its error rows, never over all.
TEST(FidelityLedger, TheSummaryAveragesOverTheRowsWithAnError) {
  auto row = [](const std::string& kind, double error, bool holds) {
    LedgerRow r;
    r.machine = "m";
    r.operation = kind + " row";
    r.kind = kind;
    r.published = 100;
    r.unit = "MOPS";
    r.model = 100 + error;
    r.errorPct = kind == "lower bound" ? 0 : error;
    r.holds = holds;
    r.grade = "primary";
    return r;
  };
  const std::string md = LedgerMarkdown(
      {row("rate", 10, true), row("time", -30, true), row("lower bound", 0, true),
       row("lower bound", 0, false)},
      "runs.csv");
  EXPECT_NE(md.find("| m | 4 | 2 | 20.00 % | 30.00 % | 1 of 2 |"), std::string::npos) << md;
}

// The model rows: PIMeval's BitSIMD-V counts priced at its DDR4-3200 timing ((R + W) × 74 tCK
// + L × 4 tCK) against the engine's cycles on pim-bitsimd-v-bank: one model against another,
// graded derived; add within 1 %, the multiply twice PIMeval's (docs/validation.md says why).
TEST(FidelityLedger, PimevalRowsPriceItsCountsAgainstTheEnginesCycles) {
  const std::vector<LedgerRow> rows = PimevalRows();
  ASSERT_EQ(rows.size(), 15u);
  for (const LedgerRow& r : rows) {
    EXPECT_EQ(r.machine, "pim-bitsimd-v-bank") << r.operation;
    EXPECT_EQ(r.kind, "model") << r.operation;
    EXPECT_EQ(r.grade, "derived") << r.operation;
    EXPECT_EQ(r.unit, "tCK") << r.operation;
    EXPECT_NE(r.source.find("a model, not a measurement"), std::string::npos) << r.operation;
    EXPECT_DOUBLE_EQ(r.errorPct, (r.model - r.published) / r.published * 100) << r.operation;
  }
  const LedgerRow& add8 = Row(rows, "add 8-bit (PIMeval ADD)");
  EXPECT_EQ(add8.published, (16 + 8) * 74 + 25 * 4);  // 1876
  EXPECT_EQ(add8.model, 1888);  // 8 full-adder steps: 16 reads, 8 writes, 8 x 12 + carry ops
  const LedgerRow& mul32 = Row(rows, "mul 32-bit (PIMeval MUL)");
  EXPECT_EQ(mul32.published, (1056 + 528) * 74 + 2080 * 4);
  EXPECT_GT(mul32.model / mul32.published, 1.9);
  EXPECT_LT(mul32.model / mul32.published, 2.0);
  EXPECT_EQ(Row(rows, "less 16-bit (PIMeval LT)").published, (32 + 1) * 74 + 49 * 4);
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

// Haines' SPD rows: his own counts (tests by kind, rays) priced by the work table on the hp-835
// profile, against his HP 9000/835 seconds; his µs per test against one test's price.
TEST(FidelityLedger, HostRowsPriceHainesCountsOnTheHp835) {
  const std::vector<LedgerRow> rows = HostRows();
  ASSERT_EQ(rows.size(), 9u);  // seven scenes, two per-test rows
  const testbed::HostProfile& hp = testbed::HostProfileNamed("hp-835");
  // tetra: 965K polygon tests, 7637K box tests; 513x513 eye rays and 46112 shadow rays; 3:48.
  TraceStats tetra;
  tetra.tests[int(ShapeKind::kPolygon)] = 965000;
  tetra.boxTests = 7637000;
  tetra.rays[int(RayKind::kPrimary)] = 513 * 513;
  tetra.rays[int(RayKind::kShadow)] = 46112;
  const LedgerRow& row = Row(rows, "SPD tetra ray tracing (Haines' counts)");
  EXPECT_EQ(row.machine, "hp-835");
  EXPECT_EQ(row.kind, "time");
  EXPECT_EQ(row.unit, "s");
  EXPECT_EQ(row.published, 3 * 60 + 48);
  EXPECT_NEAR(row.model, testbed::ModelHostTime(tetra, hp).seconds, 1e-9);
  EXPECT_DOUBLE_EQ(row.errorPct, (row.model - 228) / 228 * 100);
  EXPECT_EQ(Row(rows, "SPD gears ray tracing (Haines' counts)").published, 3600 + 2 * 60 + 31);
  // One box test: 27 flops at 2.06 MFLOPS and 15 instructions at 14 MIPS, in µs.
  const auto& box = testbed::CostOf(testbed::WorkEvent::kBoxTest);
  const LedgerRow& boxRow = Row(rows, "bounding box test (tetra)");
  EXPECT_EQ(boxRow.published, 26.71);
  EXPECT_EQ(boxRow.unit, "us");
  EXPECT_NEAR(boxRow.model, box.flops / hp.mflops.value + box.instructions / hp.mips.value,
              1e-9);
  for (const LedgerRow& r : rows) {
    EXPECT_EQ(r.grade, "primary") << r.operation;
    EXPECT_NE(r.source.find("Standard Procedural Databases README v3.14, Timings"),
              std::string::npos);
  }
}

// Every row's source is graded; the MPP's 12-bit rows are secondary and the table says so
// beside their errors, and only beside theirs.
TEST(FidelityLedger, EveryRowIsGradedAndASecondaryRowSaysSo) {
  std::vector<LedgerRow> rows = MachineRows();
  for (const LedgerRow& r : HostRows()) rows.push_back(r);
  for (const LedgerRow& r : PaperRows({{"seq", 8, 0, 0, 0, 10}, {"simd", 8, 0, 0, 0, 6}}))
    rows.push_back(r);
  for (const LedgerRow& r : rows)
    EXPECT_TRUE(r.grade == "primary" || r.grade == "secondary" || r.grade == "derived")
        << r.machine << " / " << r.operation << ": '" << r.grade << "'";
  EXPECT_EQ(Row(rows, "add 12-bit").grade, "secondary");
  EXPECT_EQ(Row(rows, "multiply 12-bit").grade, "secondary");
  EXPECT_EQ(Row(rows, "add 8-bit").grade, "primary");
  const std::string md = LedgerMarkdown(rows, "runs.csv");
  EXPECT_NE(md.find("| +0.00 % (secondary) | "), std::string::npos) << md;   // add 12-bit
  EXPECT_NE(md.find("| +0.02 % (secondary) | "), std::string::npos) << md;   // multiply 12-bit
  EXPECT_EQ(md.find("| +0.01 % (secondary) | "), std::string::npos) << md;   // add 8-bit
  // Each figure in its unit: whole numbers from 100 up, two decimals below.
  EXPECT_NE(md.find("| rate | 6553 MOPS | 6554 MOPS | +0.01 % |"), std::string::npos) << md;
  EXPECT_NE(md.find("| time | 26.71 us | 14.18 us | -46.92 % |"), std::string::npos) << md;
  const std::string csv = LedgerCsv(rows);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "machine,operation,kind,published,unit,model,error_pct,holds,grade,source");
  EXPECT_NE(csv.find(",yes,secondary,\"Batcher 1980"), std::string::npos) << csv;
}

// The per-machine summary names every machine the rows name, in the table's order, whatever
// the name: a machine added later (here a made-up "cm-2") gets its own line.
TEST(FidelityLedger, TheSummaryHasALineForEveryMachine) {
  auto row = [](const std::string& machine, const std::string& kind, double error, bool holds) {
    LedgerRow r;
    r.machine = machine;
    r.operation = "op";
    r.kind = kind;
    r.published = 100;
    r.unit = "MOPS";
    r.grade = "primary";
    r.errorPct = error;
    r.holds = holds;
    return r;
  };
  const std::vector<LedgerRow> rows = {
      row("cm-2", "rate", -10, true), row("cm-2", "time", 4, true),
      row("maspar-mp1", "rate", 2, true), row("blitzen", "lower bound", 18.9, false)};
  const std::string md = LedgerMarkdown(rows, "runs.csv");
  EXPECT_NE(md.find("| cm-2 | 2 | 2 | 7.00 % | 10.00 % | - |"), std::string::npos) << md;
  EXPECT_NE(md.find("| maspar-mp1 | 1 | 1 | 2.00 % | 2.00 % | - |"), std::string::npos) << md;
  EXPECT_NE(md.find("| blitzen | 1 | 0 | - | - | 0 of 1 |"), std::string::npos) << md;
  EXPECT_LT(md.find("| cm-2 | 2 |"), md.find("| maspar-mp1 | 1 |"));
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
  EXPECT_NE(ok.output.find("38 rows checked"), std::string::npos) << ok.output;
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
}  // namespace zephyr::ledger
