#include "hosts/methods/ledger.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "bitserial/profile.h"
#include "fixed/check.h"
#include "fixed/input_file.h"

namespace zephyr::methods {
namespace {

using bitserial::MachineProfile;

// Cycles of one fixed-point add or multiply of n-bit signed operands (result in the operands'
// format, as Batcher's table counts them: 3n+1 and n²+3n on the MPP) on one layer.
double FixedCycles(const MachineProfile& p, const std::string& op, int n) {
  bitserial::Machine m(p);
  const fixed::Format f = fixed::Format::Signed(n - 1, 0);
  bitserial::Multi a(m, f, "a"), b(m, f, "b");
  m.Report().Clear();
  bitserial::Multi r = op == "add" ? Add(a, b, f) : Mul(a, b, f);
  return m.Report().TotalCycles();
}

double Mops(const MachineProfile& p, double cycles) {
  return p.physicalPes * p.clockHz / cycles / 1e6;
}

LedgerRow Rate(const MachineProfile& p, const std::string& op, double published,
               const std::string& unit, const std::string& source, double cycles, bool bound) {
  LedgerRow r;
  r.machine = p.name;
  r.operation = op;
  r.kind = bound ? "lower bound" : "rate";
  r.published = published;
  r.unit = unit;
  r.source = source;
  r.model = Mops(p, cycles);
  r.note = fmt::format("{:g} cycles on {} PEs at {:g} MHz", cycles, p.physicalPes, p.clockHz / 1e6);
  if (bound) {
    r.holds = r.model >= published;
    r.errorPct = r.holds ? 0 : (published - r.model) / published * 100;
  } else {
    r.errorPct = (r.model - published) / published * 100;
  }
  return r;
}

}  // namespace

std::vector<LedgerRow> MachineRows() {
  std::vector<LedgerRow> rows;
  const MachineProfile mpp = bitserial::Profile("mpp");
  const std::string batcher =
      "Batcher 1980 (IEEE Trans. Computers C-29(9)), the table of operation speeds";
  // The profile's own float format: the MPP flushes to zero (floatSubnormals = 0).
  const fixed::FloatFormat f32{8, 23, mpp.floatSubnormals};
  rows.push_back(Rate(mpp, "add 8-bit", 6553, "MOPS", batcher, FixedCycles(mpp, "add", 8), false));
  rows.push_back(
      Rate(mpp, "add 12-bit", 4428, "MOPS", batcher, FixedCycles(mpp, "add", 12), false));
  rows.push_back(
      Rate(mpp, "multiply 8-bit", 1861, "MOPS", batcher, FixedCycles(mpp, "mul", 8), false));
  rows.push_back(
      Rate(mpp, "multiply 12-bit", 910, "MOPS", batcher, FixedCycles(mpp, "mul", 12), false));
  rows.push_back(Rate(mpp, "floating add 32-bit", 430, "MOPS", batcher,
                      bitserial::FloatOpCycles(mpp, "fadd", f32), false));
  rows.push_back(Rate(mpp, "floating multiply 32-bit", 216, "MOPS", batcher,
                      bitserial::FloatOpCycles(mpp, "fmul", f32), false));
  const MachineProfile blitzen = bitserial::Profile("blitzen");
  const std::string blevins = "Blevins et al. 1990 (J. Parallel Distrib. Comput. 8), abstract";
  rows.push_back(Rate(blitzen, "add 32-bit (above)", 3000, "MOPS", blevins,
                      FixedCycles(blitzen, "add", 32), true));
  rows.push_back(Rate(
      blitzen, "IEEE single multiply (above)", 450, "MFLOPS", blevins,
      bitserial::FloatOpCycles(blitzen, "fmul", fixed::FloatFormat{8, 23, blitzen.floatSubnormals}),
      true));
  return rows;
}

std::vector<SweepRun> ReadRuns(const std::string& fileName) {
  std::istringstream in(ReadInputFile(
      fileName, {"the sweep's runs", "the sweep's runs.csv (make charts TESTBED=ufmg1992)"},
      std::uintmax_t(64) << 20));
  const std::string file = PrintablePath(fileName);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) header.push_back(c);
  }
  auto column = [&](const std::string& name) {
    auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw UserError(file + ":1: no column '" + name + "'");
    return static_cast<size_t>(it - header.begin());
  };
  const size_t cm = column("method"), cn = column("objects"), ck = column("children"),
               cf = column("frame"), cb = column("ethernet_bps"), cs = column("model_s"),
               cy = column("bytes"), cp = column("pixels");
  std::vector<SweepRun> runs;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) f.push_back(c);
    if (f.size() < header.size())
      throw UserError(fmt::format("{}:{}: {} columns, the header has {}", file, number, f.size(),
                                  header.size()));
    // A count must be a whole number from `low`; a time, rate or size finite and above `low`
    // (a model time of 0 would make every finding hold by an infinite margin).
    auto num = [&](size_t c, double low, bool whole, bool strictly) {
      char* end = nullptr;
      const double v = f[c].empty() || std::isspace(static_cast<unsigned char>(f[c][0]))
                           ? std::nan("")
                           : std::strtod(f[c].c_str(), &end);
      if (!std::isfinite(v) || *end != '\0')
        throw UserError(fmt::format("{}:{}: {} '{}' is not a finite number", file, number,
                                    header[c], f[c]));
      if ((whole && (v != std::floor(v) || v > 1e9)) || v < low || (strictly && v == low))
        throw UserError(fmt::format("{}:{}: {} {} is out of range (expected {}{} {})", file,
                                    number, header[c], f[c], whole ? "a whole number " : "",
                                    strictly ? "above" : "from", low));
      return v;
    };
    SweepRun r;
    r.method = f[cm];
    r.objects = static_cast<int>(num(cn, 1, true, false));
    r.children = static_cast<int>(num(ck, 0, true, false));
    r.frame = static_cast<int>(num(cf, 0, true, false));
    r.ethernetBps = num(cb, 0, false, false);
    r.modelSeconds = num(cs, 0, false, true);
    r.bytes = num(cy, 0, false, false);
    r.pixels = num(cp, 0, false, false);
    runs.push_back(r);
  }
  if (runs.empty()) throw UserError(file + ": holds no runs (only a header)");
  return runs;
}

std::vector<RecordedRow> ReadRecorded(const std::string& file) {
  std::istringstream in(ReadInputFile(file, {"the recorded errors", "a CSV of recorded errors"},
                                      std::uintmax_t(16) << 20));
  const std::string shown = PrintablePath(file);
  std::string line;
  if (!std::getline(in, line) || line != "machine,operation,error_pct")
    throw UserError(shown + ":1: expected the header machine,operation,error_pct");
  std::vector<RecordedRow> recorded;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    const size_t a = line.find(','), b = line.rfind(',');
    if (a == std::string::npos || a == b)
      throw UserError(shown + ":" + std::to_string(number) +
                      ": expected machine,operation,error_pct");
    const std::string error = line.substr(b + 1);
    char* end = nullptr;
    const double v = error.empty() ? 0 : std::strtod(error.c_str(), &end);
    if (error.empty() || end != error.c_str() + error.size() || !std::isfinite(v) ||
        std::isspace(static_cast<unsigned char>(error[0])))
      throw UserError(shown + ":" + std::to_string(number) + ": error_pct '" + error +
                      "' is not a finite number");
    recorded.push_back({number, line.substr(0, a), line.substr(a + 1, b - a - 1), v});
  }
  if (recorded.empty()) throw UserError(shown + ": holds no recorded rows");
  return recorded;
}

namespace {
// A check over pairs "a below b": the worst margin (b − a) ÷ b over every pair the sweep has.
struct Check {
  double worst = std::numeric_limits<double>::infinity();
  std::string worstAt;
  int pairs = 0;
  void Below(double a, double b, const std::string& where) {
    ++pairs;
    const double margin = (b - a) / b * 100;
    if (margin < worst) worst = margin, worstAt = where;
  }
};

LedgerRow CheckRow(const std::string& what, const std::string& source, const Check& c) {
  LedgerRow r;
  r.machine = "paper (ufmg1992)";
  r.operation = what;
  r.kind = "check";
  r.unit = "% margin";
  r.source = source;
  r.model = c.worst;
  r.holds = c.worst > 0;
  r.errorPct = r.holds ? 0 : std::max(0.0, -c.worst);
  r.note = fmt::format("worst of {} pairs: {}", c.pairs, c.worstAt);
  return r;
}
}  // namespace

std::vector<LedgerRow> PaperRows(const std::vector<SweepRun>& runs) {
  // The default Ethernet only (ethernet_bps 0): the what-if bandwidths are not the paper's.
  auto find = [&](const std::string& m, int n, int k, int f) -> const SweepRun* {
    for (const SweepRun& r : runs)
      if (r.method == m && r.objects == n && r.children == k && r.frame == f && r.ethernetBps == 0)
        return &r;
    return nullptr;
  };
  std::vector<int> counts, children, frames;
  // The paper's own testbed: 2, 4 and 8 children, frames of 32 to 128 pixels (§6); the sweep's
  // points past the paper (more children, smaller frames) are not its findings.
  for (const SweepRun& r : runs) {
    if (r.ethernetBps != 0) continue;
    counts.push_back(r.objects);
    if (r.children >= 2 && r.children <= 8) children.push_back(r.children);
    if (r.frame >= 32 && r.frame <= 128) frames.push_back(r.frame);
  }
  for (auto* v : {&counts, &children, &frames}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  std::vector<LedgerRow> rows;
  auto add = [&](const std::string& what, const std::string& source, const Check& c) {
    if (c.pairs) rows.push_back(CheckRow(what, source, c));
  };
  Check fig5, fig6, fig79, fig10, fig11, fig12;
  const int maxK = children.empty() ? 0 : children.back();
  const int minF = frames.empty() ? 0 : frames.front();
  for (int n : counts) {
    const SweepRun *seq = find("seq", n, 0, 0), *simd = find("simd", n, 0, 0);
    if (seq && simd)
      fig5.Below(simd->modelSeconds, seq->modelSeconds, fmt::format("{} objects", n));
    for (size_t i = 1; i < children.size(); ++i) {
      const SweepRun *few = find("dist", n, children[i - 1], minF),
                     *more = find("dist", n, children[i], minF);
      if (few && more)
        fig6.Below(more->modelSeconds, few->modelSeconds,
                   fmt::format("{} objects, {} vs {} children", n, children[i], children[i - 1]));
    }
    for (int k : children)
      for (size_t i = 1; i < frames.size(); ++i) {
        const SweepRun *small = find("hetero", n, k, frames[i - 1]),
                       *big = find("hetero", n, k, frames[i]);
        if (small && big)
          fig79.Below(small->modelSeconds, big->modelSeconds,
                      fmt::format("{} objects, {} children, frame {} vs {}", n, k, frames[i - 1],
                                  frames[i]));
      }
    const SweepRun *d = find("dist", n, maxK, minF), *h = find("hetero", n, maxK, minF);
    if (seq && simd && d && h) {
      const std::string at = fmt::format("{} objects", n);
      fig12.Below(h->modelSeconds, d->modelSeconds, at + ": heterogeneous vs distributed");
      fig12.Below(d->modelSeconds, simd->modelSeconds, at + ": distributed vs SIMD/sequential");
      fig12.Below(simd->modelSeconds, seq->modelSeconds, at + ": SIMD/sequential vs sequential");
    }
  }
  // Figs 10–11 at the sweep's reference count (64 objects) and most children: as frames
  // shrink, heterogeneous moves fewer bytes and its children process fewer pixels (the frames
  // the array found empty are skipped).
  for (size_t i = 1; i < frames.size(); ++i) {
    const SweepRun *small = find("hetero", 64, maxK, frames[i - 1]),
                   *big = find("hetero", 64, maxK, frames[i]);
    if (small && big) {
      const std::string at = fmt::format("frame {} vs {}", frames[i - 1], frames[i]);
      fig10.Below(small->bytes, big->bytes, at);
      fig11.Below(small->pixels, big->pixels, at);
    }
  }
  add("Fig 5: SIMD/sequential below sequential at every object count", "paper §6, Fig 5", fig5);
  add("Fig 6: more children take less time (distributed)", "paper §6, Fig 6", fig6);
  add("Figs 7-9: smaller frames take less time (heterogeneous)", "paper §6, Figs 7-9", fig79);
  add("Fig 10: smaller frames move fewer bytes (heterogeneous)", "paper §6, Fig 10", fig10);
  add("Fig 11: smaller frames leave the children fewer pixels (heterogeneous)", "paper §6, Fig 11",
      fig11);
  add("Fig 12: heterogeneous < distributed < SIMD/sequential < sequential", "paper §6, Fig 12",
      fig12);
  return rows;
}

std::string LedgerCsv(const std::vector<LedgerRow>& rows) {
  std::string s = "machine,operation,kind,published,unit,model,error_pct,holds,source\n";
  for (const LedgerRow& r : rows)
    s += fmt::format("{},{},{},{:g},{},{:.6g},{:.4f},{},\"{}\"\n", r.machine, r.operation, r.kind,
                     r.published, r.unit, r.model, r.errorPct, r.holds ? "yes" : "no", r.source);
  return s;
}

std::string LedgerMarkdown(const std::vector<LedgerRow>& rows, const std::string& runsFile) {
  std::string s =
      "# The fidelity ledger\n\n"
      "Every published figure the model can be set against, with the model's value and its\n"
      "error. Written by `make validate` (`zephyr validate --runs " +
      runsFile +
      "`); do not edit by hand. Machine rows: the engine's cycles on the profile's file\n"
      "(bitserial/profiles/, docs/bitserial.md), rate = PEs × clock ÷ cycles. Paper rows: the\n"
      "paper's findings on the modelled 1992 seconds of the testbed sweep (docs/testbed.md),\n"
      "the margin the worst point of the sweep has (negative: the finding does not hold there).\n"
      "`make test` fails if any row's error grows past tools/validation_recorded.csv.\n\n"
      "| machine | operation | kind | published | model | error | holds | source | how |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  std::map<std::string, std::pair<double, double>> perMachine;  // sum |error|, max |error|
  std::map<std::string, int> rates;
  for (const LedgerRow& r : rows) {
    const bool check = r.kind == "check";
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", r.machine, r.operation,
                     r.kind, check ? "holds" : fmt::format("{:g} {}", r.published, r.unit),
                     check ? fmt::format("{:+.1f} % margin", r.model)
                           : fmt::format("{:.0f} {}", r.model, r.unit),
                     r.kind == "rate" ? fmt::format("{:+.2f} %", r.errorPct)
                                      : fmt::format("{:.1f} % short", r.errorPct),
                     r.kind == "rate" ? "" : (r.holds ? "yes" : "**no**"), r.source, r.note);
    if (r.kind == "rate") {
      auto& [sum, mx] = perMachine[r.machine];
      sum += std::fabs(r.errorPct);
      mx = std::max(mx, std::fabs(r.errorPct));
      ++rates[r.machine];
    }
  }
  s += "\n| machine | rate rows | mean abs error | max abs error |\n|---|---|---|---|\n";
  for (const auto& [m, e] : perMachine)
    s += fmt::format("| {} | {} | {:.2f} % | {:.2f} % |\n", m, rates[m], e.first / rates[m],
                     e.second);
  int bounds = 0, met = 0, checks = 0, held = 0;
  for (const LedgerRow& r : rows) {
    if (r.kind == "lower bound") ++bounds, met += r.holds;
    if (r.kind == "check") ++checks, held += r.holds;
  }
  s += fmt::format("\nBounds met: {} of {}. Paper findings holding: {} of {}.\n", met, bounds, held,
                   checks);
  s += "\n![model against published](results/validation.png)\n";
  return s;
}

}  // namespace zephyr::methods
