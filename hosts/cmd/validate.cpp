// hosts/cmd/validate.cpp — `zephyr validate`: the fidelity ledger (hosts/ledger/ledger.h;
// docs/validation.md), written by `make validate`.
//
//   zephyr validate --runs docs/results/testbed-ufmg1992/runs.csv --out docs/validation.md
//                   --csv docs/results/validation.csv
//   zephyr validate --runs ... --check tools/validation_recorded.csv   # fails if an error grew
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include "fixed/check.h"
#include "fixed/input_file.h"
#include "hosts/cmd/command.h"
#include "hosts/io/output_file.h"
#include "hosts/ledger/ledger.h"

namespace zephyr::ledger {
namespace {

struct ValidateOptions {
  std::string runs, out, csv, check;
};

// The recorded errors (tools/validation_recorded.csv: machine,operation,error_pct): a row whose
// error grew past its record, or a recorded row the ledger lacks, fails.
int CheckRecorded(const std::vector<LedgerRow>& rows, const std::string& file) {
  int failed = 0;
  const std::vector<RecordedRow> recordedRows = ReadRecorded(file);
  for (const RecordedRow& rec : recordedRows) {
    const int number = rec.line;
    const std::string &machine = rec.machine, &op = rec.operation;
    const double recorded = rec.errorPct;
    const LedgerRow* row = nullptr;
    for (const LedgerRow& r : rows)
      if (r.machine == machine && r.operation == op) row = &r;
    if (!row) {
      std::fprintf(stderr, "validate: %s:%d: recorded row '%s / %s' is missing\n", file.c_str(),
                   number, machine.c_str(), op.c_str());
      ++failed;
    } else if (std::fabs(row->errorPct) > std::fabs(recorded) + 1e-4) {  // recorded to 4 places
      std::fprintf(stderr, "validate: %s / %s: error %.4f %% grew past the recorded %.4f %%\n",
                   machine.c_str(), op.c_str(), row->errorPct, recorded);
      ++failed;
    }
  }
  std::printf("validate: %zu rows checked against %s, %d worse\n", recordedRows.size(),
              file.c_str(), failed);
  return failed;
}

CommandRegistration validateCommand("validate", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "validate", "The fidelity ledger: published figures against the model (docs/validation.md)");
  auto o = std::make_shared<ValidateOptions>();
  cmd->add_option("--runs", o->runs,
                  "The testbed sweep's runs.csv (make charts TESTBED=ufmg1992) for the paper rows");
  cmd->add_option("--out", o->out, "Write the ledger as Markdown here");
  cmd->add_option("--csv", o->csv, "Write the ledger as CSV here");
  cmd->add_option("--check", o->check,
                  "Fail if a row's error grew past this file's (tools/validation_recorded.csv)");
  cmd->callback([o] {
    // The output pre-flight every command has: neither output may be an input of the run
    // (--csv naming the --check file would overwrite the record it is checked against).
    CheckOutputs({{"--out", o->out}, {"--csv", o->csv}},
                 {{"the sweep's runs (--runs)", o->runs}, {"the recorded errors (--check)", o->check}});
    std::vector<LedgerRow> rows = MachineRows();
    for (LedgerRow& r : HostRows()) rows.push_back(r);
    for (LedgerRow& r : PimevalRows()) rows.push_back(r);
    if (!o->runs.empty())
      for (LedgerRow& r : PaperRows(ReadRuns(o->runs))) rows.push_back(r);
    const std::string csv = LedgerCsv(rows);
    if (!o->out.empty()) WriteOutputFile(o->out, "ledger", LedgerMarkdown(rows, o->runs));
    if (!o->csv.empty()) WriteOutputFile(o->csv, "ledger CSV", csv);
    if (o->out.empty() && o->csv.empty()) std::fputs(csv.c_str(), stdout);
    if (!o->check.empty() && CheckRecorded(rows, o->check) != 0)
      throw UserError("the ledger got worse than " + o->check + " (rows above)");
  });
});

}  // namespace
}  // namespace zephyr::ledger
