// build/bin/kernels — the kernel suite (docs/kernels.md; `make kernels`).
//
//   build/bin/kernels                               # every kernel, every profile, 2 sizes
//   build/bin/kernels --kernels sort,scan --profiles mpp --one-layer
//   build/bin/kernels --markdown docs/kernels.md
//
// For every kernel of tools/kernels/suite.h and every built-in profile
// (kernels::GridProfiles(): those with a 2-D mesh), at one layer (the profile's PEs) and at the
// largest size up to --max-elements (default 2^20) that fits the profile's PE memory: the array run
// timed on the Highway target the machine picks by itself, then the same run on every compiled
// target the CPU has, each checked bit for bit against plain C++ and for the same cycles.
// Prints one table per kernel (machine cycles, modelled seconds, the emulator's host time,
// plain C++'s, cycles by class). Exit 1 if any result differs, 2 on bad arguments.
#include <fmt/format.h>
#include <hwy/targets.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "hosts/cmd/command.h"
#include "tools/kernels/suite.h"

namespace {

using namespace zephyr;
using kernels::KernelRun;

// A comma-separated list of `flag`; an empty item (",", "a,,b", "a,") is named, never skipped:
// `--profiles ,` would otherwise be an empty table.
std::vector<std::string> SplitList(const std::string& s, const std::string& flag) {
  std::vector<std::string> out;
  size_t at = 0;
  while (true) {
    const size_t comma = s.find(',', at);
    const std::string item = s.substr(at, comma == std::string::npos ? comma : comma - at);
    if (item.empty())
      throw UserError(fmt::format("{} '{}': an empty item (a comma-separated list of names)",
                                  flag, s));
    out.push_back(item);
    if (comma == std::string::npos) return out;
    at = comma + 1;
  }
}

std::string FirstLine(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) {
      const size_t colon = line.find(':');
      return colon == std::string::npos ? line
                                        : line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "unknown";
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five;
  in >> one >> five;
  return one.empty() ? "unknown" : one + " (1 min), " + five + " (5 min)";
}

// The columns of one kernel's table.
const char* const kHeader[] = {"profile",      "elements",    "layers",      "cycles",
                               "without host", "modelled s",  "emulator s",  "plain C++ s",
                               "alu",          "internalMem", "externalMem", "communication",
                               "reduction",    "host"};

std::vector<std::string> Row(const KernelRun& r) {
  using bitserial::CycleClass;
  const auto& rep = r.report;
  auto cyc = [](double c) { return fmt::format("{:.0f}", c); };
  return {r.profile,
          std::to_string(r.elements),
          std::to_string(r.layers),
          cyc(rep.TotalCycles()),
          cyc(rep.TotalCycles() - rep.ClassCycles(CycleClass::kHost)),
          fmt::format("{:.3g}", rep.ModelledSeconds()),
          fmt::format("{:.3g}", r.hostSeconds),
          fmt::format("{:.3g}", r.plainSeconds),
          cyc(rep.ClassCycles(CycleClass::kAlu)),
          cyc(rep.ClassCycles(CycleClass::kInternalMemory)),
          cyc(rep.ClassCycles(CycleClass::kExternalMemory)),
          cyc(rep.ClassCycles(CycleClass::kCommunication)),
          cyc(rep.ClassCycles(CycleClass::kReduction)),
          cyc(rep.ClassCycles(CycleClass::kHost))};
}

std::string TextTable(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width(std::size(kHeader));
  for (size_t c = 0; c < width.size(); ++c) width[c] = std::string(kHeader[c]).size();
  for (const auto& r : rows)
    for (size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], r[c].size());
  std::string out;
  auto line = [&](auto cell) {
    for (size_t c = 0; c < width.size(); ++c)
      out += c == 0 ? fmt::format("  {:<{}}", cell(c), width[c])
                    : fmt::format("  {:>{}}", cell(c), width[c]);
    out += '\n';
  };
  line([&](size_t c) { return std::string(kHeader[c]); });
  for (const auto& r : rows) line([&](size_t c) { return r[c]; });
  return out;
}

std::string MarkdownTable(const std::vector<std::vector<std::string>>& rows) {
  std::string out = "|";
  for (const char* h : kHeader) out += fmt::format(" {} |", h);
  out += "\n|---|";
  for (size_t c = 1; c < std::size(kHeader); ++c) out += "---:|";
  out += '\n';
  for (const auto& r : rows) {
    out += "|";
    for (const auto& cell : r) out += fmt::format(" {} |", cell);
    out += '\n';
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("The SIMD-array kernel suite on every machine profile of the emulated Zephyr");
  std::string profileList, kernelList, markdown;
  int64_t maxElements = int64_t{1} << 20;
  bool oneLayer = false;
  uint64_t seed = 1;
  app.add_option("--profiles", profileList,
                 "Comma-separated profiles (default: every built-in one)");
  app.add_option("--kernels", kernelList,
                 "Comma-separated kernels (default: all: vadd, dot, matvec, histogram, scan, "
                 "sort, stencil, life, blur)");
  app.add_option("--max-elements", maxElements,
                 "The many-layer size: a power-of-two multiple of each profile's PEs, halved "
                 "until the kernel fits the profile's PE memory")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 24));
  app.add_flag("--one-layer", oneLayer, "Only the one-layer size (the profile's PEs)");
  app.add_option("--seed", seed, "Seed of the random inputs");
  app.add_option("--markdown", markdown, "Also write the tables to this file (docs/kernels.md)");
  // An empty value is refused as by every zephyr command (`--kernels ''` ran all).
  RefuseEmptyValues(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help: 0; a bad flag or value: its message, 2
  }

  std::vector<std::unique_ptr<kernels::Kernel>> suite = kernels::AllKernels();
  std::vector<kernels::Kernel*> chosen;
  std::vector<std::string> profiles;
  try {
    profiles = profileList.empty() ? kernels::GridProfiles() : SplitList(profileList, "--profiles");
    for (const auto& p : profiles) bitserial::Profile(p);  // an unknown name fails here
    const std::vector<std::string> names =
        kernelList.empty() ? std::vector<std::string>{} : SplitList(kernelList, "--kernels");
    for (auto& k : suite)
      if (names.empty() || std::find(names.begin(), names.end(), k->Name()) != names.end())
        chosen.push_back(k.get());
    for (const auto& n : names)
      if (std::none_of(suite.begin(), suite.end(), [&](auto& k) { return k->Name() == n; })) {
        std::string known;
        for (auto& k : suite) known += (known.empty() ? "" : ", ") + k->Name();
        throw UserError(fmt::format("unknown kernel '{}' (known: {})", n, known));
      }
    if (!oneLayer)
      for (const auto& p : profiles) {
        const int pes = bitserial::Profile(p).physicalPes;
        if (maxElements < pes || maxElements % pes != 0 ||
            ((maxElements / pes) & (maxElements / pes - 1)) != 0)
          throw UserError(
              fmt::format("--max-elements {} is not a power-of-two multiple of profile {}'s {} PEs",
                          maxElements, p, pes));
      }
  } catch (const UserError& e) {
    fmt::print(stderr, "kernels: {}\n", e.what());
    return 2;
  }

  std::vector<std::string> targetNames;
  for (int64_t t : hwy::SupportedAndGeneratedTargets()) targetNames.push_back(hwy::TargetName(t));
  std::string md = fmt::format(
      "# Kernels on every machine profile\n\n"
      "Written by `make kernels` (build/bin/kernels, tools/kernels/; the patterns are taught "
      "in docs/programming.md). Every figure below comes from that run; rerun it for "
      "current ones.\n\n"
      "Each kernel is a program on the library's API (tools/kernels/kernels.h; Life and blur "
      "are tools/examples/), run on a machine with one virtual PE per element. Its cycles "
      "are the whole array run: the inputs loaded from the host, the program, the result "
      "read back (the `host` class is the transfers; *without host* the program alone). *Modelled "
      "s* is the cycles at the "
      "profile's clock; *emulator s* is this host's wall time for the same run (best of up "
      "to five), *plain C++ s* the plain version's (best of batches), timed in the same "
      "run on the same inputs. Sizes: one layer (the profile's PEs) and 2^20 elements, or "
      "the largest power-of-two number of layers whose program fits the profile's PE "
      "memory (the MPP has 1024 bits per PE and no external memory); the PIM suites' own "
      "default input sizes are not reproduced. Every result equals "
      "the plain C++ version's bit for bit, with the same cycles, on every Highway target "
      "of this CPU: {}.\n\n"
      "Host: {} ({} hardware threads); load average at the start {}.\n",
      fmt::join(targetNames, ", "), FirstLine("/proc/cpuinfo", "model name"),
      std::thread::hardware_concurrency(), LoadAverage());

  bool allEqual = true;
  for (kernels::Kernel* k : chosen) {
    std::vector<std::vector<std::string>> rows;
    std::vector<std::string> notes;
    fmt::print("{} ({}): {}\n", k->Title(), k->Name(), k->What());
    for (const auto& profile : profiles) {
      try {
        const int pes = bitserial::Profile(profile).physicalPes;
        std::vector<KernelRun> runs;
        runs.push_back(kernels::RunKernel(*k, profile, pes, {}));
        if (!oneLayer && maxElements > pes)
          runs.push_back(kernels::RunLargestFitting(*k, profile, maxElements, {}));
        for (const KernelRun& run : runs) {
          std::vector<std::string> bad;
          if (!run.difference.empty()) bad.push_back(run.target + ": " + run.difference);
          for (int64_t t : hwy::SupportedAndGeneratedTargets()) {
            hwy::SetSupportedTargetsForTest(t);
            const KernelRun check = kernels::RunKernel(*k, profile, run.elements, {false, 1});
            if (!check.difference.empty())
              bad.push_back(check.target + ": " + check.difference);
            else if (!check.report.SameCharges(run.report))
              bad.push_back(check.target + ": other cycles than " + run.target + "'s");
          }
          hwy::SetSupportedTargetsForTest(0);
          for (const auto& b : bad)
            fmt::print(stderr, "{} on {}, {} elements: differs from plain C++: {}\n", k->Name(),
                       profile, run.elements, b);
          allEqual = allEqual && bad.empty();
          rows.push_back(Row(run));
          if (!run.note.empty()) notes.push_back(fmt::format("{}: {}.", profile, run.note));
        }
      } catch (const UserError& e) {
        notes.push_back(fmt::format("{}: not run: {}", profile, e.what()));
        fmt::print(stderr, "{} on {}: {}\n", k->Name(), profile, e.what());
      }
    }
    fmt::print("{}", TextTable(rows));
    for (const auto& n : notes) fmt::print("  {}\n", n);
    fmt::print("\n");
    std::string what = k->What();
    what[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(what[0])));
    md += fmt::format("\n## {} (`{}`)\n\n{}.\n\n{}", k->Title(), k->Name(), what,
                      MarkdownTable(rows));
    for (const auto& n : notes) md += fmt::format("\n{}\n", n);
  }
  md += fmt::format("\nLoad average at the end: {}.\n", LoadAverage());
  if (!allEqual) {
    fmt::print(stderr, "kernels: some results differ from plain C++ (above)\n");
    return 1;
  }
  if (!markdown.empty()) {
    std::ofstream out(markdown);
    out << md;
    if (!out.flush()) {
      fmt::print(stderr, "kernels: cannot write {}\n", markdown);
      return 2;
    }
    fmt::print("wrote {}\n", markdown);
  }
  return 0;
}
