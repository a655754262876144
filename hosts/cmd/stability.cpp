// hosts/cmd/stability.cpp — `zephyr stability`: the flags and the CSV file of the stability
// study of the ray–sphere test (hosts/trace/stability.h).
//
//   zephyr stability distance --out FILE.csv   error against distance for a small, far sphere
//   zephyr stability overflow --out FILE.csv   largest scene extent each fixed format holds
#include "hosts/trace/stability.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/io/output_file.h"

namespace zephyr {
namespace {

// A CSV on standard output ("-") or written atomically to a file (hosts/io/output_file.h);
// the file's temporary is created up front, so a bad path fails before the study runs.
class CsvOut {
 public:
  explicit CsvOut(const std::string& path) {
    if (path != "-") file_.emplace(path, "CSV file");
  }
  std::FILE* Stream() const { return file_ ? file_->Stream() : stdout; }
  void Commit() {
    if (file_) return file_->Commit();
    if (std::fflush(stdout) != 0) throw UserError("cannot write the CSV to standard output");
  }

 private:
  std::optional<OutputFile> file_;
};

// The CSV at `out`, written by `study`, committed only when it has all been written.
template <class Study>
void WriteCsv(const std::string& out, Study&& study) {
  CsvOut csv(out);
  study(csv.Stream());
  csv.Commit();
}

CommandRegistration reg("stability", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "stability", "Where the ray-sphere test fails: error vs distance, overflow vs extent (CSV)");
  cmd->require_subcommand(1);

  struct Args {
    std::string out = "-";
    std::string formats = "float32,float64,s15.16,s23.24,s31.32";  // comma-separated
    int rays = 256, maxLog2 = 24, steps = 2, fracBits = 16, maxIntBits = 32, overflowRays = 16;
  };
  auto a = std::make_shared<Args>();

  auto* dist = cmd->add_subcommand(
      "distance",
      "Error against distance: a radius-1 sphere at D = 2^(k/steps), naive vs Hearn-Baker");
  dist->add_option("--out", a->out, "CSV file ('-' = standard output)")->capture_default_str();
  dist->add_option("--formats", a->formats,
                   "Formats, comma-separated: float32, float64, sI.F (fixed)")
      ->capture_default_str();
  AddInteger(*dist, "--rays", a->rays, 1, stability::kMaxFanRays,
             "Rays in the fan (closest approach 0..1.25 r)");
  AddInteger(*dist, "--max-log2", a->maxLog2, 1, 60, "Largest distance 2^N");
  AddInteger(*dist, "--steps", a->steps, 1, 1024, "Distances per octave");
  dist->callback([a] {
    CheckOutputs({{"--out", a->out}});
    // One string split here, not CLI11's delimiter: an empty item is named, and a list that
    // is all commas cannot make the option take the next flag as its value.
    std::vector<stability::StudyFormat> formats;
    for (size_t start = 0;;) {
      const size_t comma = a->formats.find(',', start);
      const std::string name = a->formats.substr(start, comma - start);
      if (name.empty())
        throw UserError("--formats '" + a->formats +
                        "': an empty item (a comma-separated list of float32, float64, sI.F)");
      formats.push_back(stability::StudyFormat::Parse(name));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    WriteCsv(a->out, [&](std::FILE* f) {
      stability::WriteDistanceStudy(f, formats, a->rays, a->maxLog2, a->steps);
    });
  });

  auto* over = cmd->add_subcommand(
      "overflow", "Largest scene extent each fixed format sI.F holds, naive vs Hearn-Baker");
  over->add_option("--out", a->out, "CSV file ('-' = standard output)")->capture_default_str();
  AddInteger(*over, "--frac-bits", a->fracBits, 4, 64, "Fraction bits F");
  AddInteger(*over, "--max-int-bits", a->maxIntBits, 2, fixed::kMaxWidth,
             "Integer bits I from 2 to this (I + F + 1 within 128)");
  AddInteger(*over, "--rays", a->overflowRays, 1, stability::kMaxFanRays, "Rays in the fan");
  over->callback([a] {
    if (a->maxIntBits + a->fracBits + 1 > fixed::kMaxWidth)
      throw UserError(fmt::format(
          "--max-int-bits {}: with --frac-bits {} the widest format would be {} bits, "
          "more than the {} of fixed/",
          a->maxIntBits, a->fracBits, a->maxIntBits + a->fracBits + 1, fixed::kMaxWidth));
    CheckOutputs({{"--out", a->out}});
    WriteCsv(a->out, [&](std::FILE* f) {
      stability::WriteOverflowStudy(f, a->fracBits, a->maxIntBits, a->overflowRays);
    });
  });
});

}  // namespace
}  // namespace zephyr
