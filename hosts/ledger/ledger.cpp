#include "hosts/ledger/ledger.h"

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
#include "hosts/testbed/host_profile.h"

namespace zephyr::ledger {
namespace {

using bitserial::MachineProfile;

// Cycles of one fixed-point operation (add, sub, mul, less, min) of n-bit signed operands on
// one layer, the result in the operands' format (less: one bit), as Batcher's table counts an
// add and a multiply (3n+1 and n²+3n on the MPP) and PIMeval's table every operation.
double FixedCycles(const MachineProfile& p, const std::string& op, int n) {
  bitserial::Machine m(p);
  const fixed::Format f = fixed::Format::Signed(n - 1, 0);
  bitserial::Multi a(m, f, "a"), b(m, f, "b");
  m.Report().Clear();
  if (op == "add") Add(a, b, f);
  else if (op == "sub") Sub(a, b, f);
  else if (op == "mul") Mul(a, b, f);
  else if (op == "less") Less(a, b);
  else Min(a, b, f);
  return m.Report().TotalCycles();
}

double Mops(const MachineProfile& p, double cycles) {
  return p.physicalPes * p.clockHz / cycles / 1e6;
}

LedgerRow Rate(const MachineProfile& p, const std::string& op, double published,
               const std::string& unit, const std::string& source, const std::string& grade,
               double cycles, bool bound) {
  LedgerRow r;
  r.machine = p.name;
  r.operation = op;
  r.kind = bound ? "lower bound" : "rate";
  r.published = published;
  r.unit = unit;
  r.source = source;
  r.grade = grade;
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
  // Grades (docs/validation.md, "Grades"): the 8-bit and floating rows cite Batcher's table
  // itself; the 12-bit rows are known to us only from a reproduction of that table.
  const std::string batcher =
      "Batcher 1980 (IEEE Trans. Computers C-29(9)), the table of operation speeds";
  const std::string batcherSecondhand =
      "Batcher 1980 (IEEE Trans. Computers C-29(9)), the table of operation speeds, known here "
      "only from a reproduction of the table (the publication not read for these rows)";
  // The profile's own float format: the MPP flushes to zero (floatSubnormals = 0).
  const fixed::FloatFormat f32{8, 23, mpp.floatSubnormals};
  rows.push_back(Rate(mpp, "add 8-bit", 6553, "MOPS", batcher, "primary",
                      FixedCycles(mpp, "add", 8), false));
  rows.push_back(Rate(mpp, "add 12-bit", 4428, "MOPS", batcherSecondhand, "secondary",
                      FixedCycles(mpp, "add", 12), false));
  rows.push_back(Rate(mpp, "multiply 8-bit", 1861, "MOPS", batcher, "primary",
                      FixedCycles(mpp, "mul", 8), false));
  rows.push_back(Rate(mpp, "multiply 12-bit", 910, "MOPS", batcherSecondhand, "secondary",
                      FixedCycles(mpp, "mul", 12), false));
  rows.push_back(Rate(mpp, "floating add 32-bit", 430, "MOPS", batcher, "primary",
                      bitserial::FloatOpCycles(mpp, "fadd", f32), false));
  rows.push_back(Rate(mpp, "floating multiply 32-bit", 216, "MOPS", batcher, "primary",
                      bitserial::FloatOpCycles(mpp, "fmul", f32), false));
  const MachineProfile blitzen = bitserial::Profile("blitzen");
  const std::string blevins = "Blevins et al. 1990 (J. Parallel Distrib. Comput. 8), abstract";
  rows.push_back(Rate(blitzen, "add 32-bit (above)", 3000, "MOPS", blevins, "primary",
                      FixedCycles(blitzen, "add", 32), true));
  rows.push_back(Rate(
      blitzen, "IEEE single multiply (above)", 450, "MFLOPS", blevins, "primary",
      bitserial::FloatOpCycles(blitzen, "fmul", fixed::FloatFormat{8, 23, blitzen.floatSubnormals}),
      true));
  return rows;
}

namespace {

// PIMeval's BitSIMD-V performance table (PIMeval, Siddique, Guo et al., IISWC 2024:
// libpimeval/src/pimPerfEnergyTables.cpp, PIM_DEVICE_BITSIMD_V): row reads, row writes and
// logic ops of one operation on signed n-bit elements (PIM_INT8, PIM_INT16, PIM_INT32).
struct PimevalOp {
  const char* op;  // our name: add, sub, mul, less, min
  const char* cmd;  // PIMeval's PimCmdEnum
  int bits;
  int reads, writes, logic;
};
constexpr PimevalOp kPimevalBitsimdV[] = {
    {"add", "ADD", 8, 16, 8, 25},      {"add", "ADD", 16, 32, 16, 49},
    {"add", "ADD", 32, 64, 32, 97},    {"sub", "SUB", 8, 16, 8, 25},
    {"sub", "SUB", 16, 32, 16, 49},    {"sub", "SUB", 32, 64, 32, 97},
    {"mul", "MUL", 8, 72, 36, 136},    {"mul", "MUL", 16, 272, 136, 528},
    {"mul", "MUL", 32, 1056, 528, 2080}, {"less", "LT", 8, 16, 1, 25},
    {"less", "LT", 16, 32, 1, 49},     {"less", "LT", 32, 64, 1, 97},
    {"min", "MIN", 8, 32, 8, 41},      {"min", "MIN", 16, 64, 16, 81},
    {"min", "MIN", 32, 128, 32, 161},
};
// PIMeval's BitSIMD-V prices (pimParamsDDRDram.h: a row read or write is tRAS + tRP, a logic op
// tCCD_S) with its DDR4-3200 timing (configs/taco/DDR4_8Gb_x16_3200.ini: tRAS 52, tRP 22,
// tCCD_S 4), in DDR4 command clocks (tCK): the same figures the pim-bitsimd-v-bank profile's
// readInternal, writeInternal and (a third of) aluStep were fixed from.
constexpr double kPimevalRowTck = 52 + 22, kPimevalLogicTck = 4;

const char* const kPimeval =
    "PIMeval's BitSIMD-V table (PIMeval, Siddique, Guo et al., IISWC 2024: libpimeval/src/"
    "pimPerfEnergyTables.cpp: row reads, writes, logic ops) priced at its DDR4-3200 timing "
    "(tRAS + tRP = 74 tCK a row, tCCD_S = 4 tCK a logic op); a model, not a measurement";

}  // namespace

std::vector<LedgerRow> PimevalRows() {
  std::vector<LedgerRow> rows;
  const MachineProfile bank = bitserial::Profile("pim-bitsimd-v-bank");
  for (const PimevalOp& o : kPimevalBitsimdV) {
    LedgerRow r;
    r.machine = bank.name;
    r.operation = fmt::format("{} {}-bit (PIMeval {})", o.op, o.bits, o.cmd);
    r.kind = "model";
    r.published = (o.reads + o.writes) * kPimevalRowTck + o.logic * kPimevalLogicTck;
    r.unit = "tCK";
    r.source = kPimeval;
    r.grade = "derived";
    r.model = FixedCycles(bank, o.op, o.bits);
    r.errorPct = (r.model - r.published) / r.published * 100;
    r.note = fmt::format("PIMeval {}R {}W {}L; the engine's schedule on one layer of {}", o.reads,
                         o.writes, o.logic, bank.name);
    rows.push_back(r);
  }
  return rows;
}

namespace {
// Haines, Standard Procedural Databases README v3.14, "Timings": ray-tracing time on an HP
// 9000/835 (512x512 pixels, 513x513 eye rays, depth 5; the "Ray-Tracing" column, without input
// and setup) and that tracer's ray-object tests by kind, in thousands ("K" = 1000); and
// "Database Analysis": the reflect, refract and shadow rays of each scene (eye rays 513x513).
struct SpdTiming {
  const char* scene;
  double seconds;                      // h:mm:ss of the Timings table, in seconds
  double polygonK, sphereK, coneK, boxK;  // tests, thousands (cylinder/cone: coneK)
  double reflect, refract, shadow;     // rays
};
constexpr SpdTiming kHainesHp835[] = {
    {"balls", 24 * 60 + 56, 822, 6197, 0, 51726, 175095, 0, 954368},
    {"gears", 3600 + 2 * 60 + 31, 13703, 0, 0, 107105, 304643, 207564, 2246955},
    {"mount", 18 * 60 + 49, 4076, 3978, 0, 31106, 354769, 354769, 412922},
    {"rings", 53 * 60 + 41, 1045, 5315, 16298, 91591, 315236, 0, 1085002},
    {"teapot", 25 * 60 + 38, 7281, 0, 0, 57050, 225248, 0, 407656},
    {"tetra", 3 * 60 + 48, 965, 0, 0, 7637, 0, 0, 46112},
    {"tree", 11 * 60 + 36, 479, 524, 1319, 22002, 0, 0, 1097419},
};
constexpr double kEyeRays = 513.0 * 513.0;
// The same README's tetra statistics: microseconds per test of that tracer on the 835.
constexpr double kHainesBoxMicros = 26.71, kHainesPolygonMicros = 36.77;

const char* const kHaines =
    "Haines, Standard Procedural Databases README v3.14, Timings "
    "(realtimerendering.com/resources/SPD)";

LedgerRow HostTimeRow(const std::string& op, double published, const std::string& unit,
                      double model, const std::string& note) {
  LedgerRow r;
  r.machine = "hp-835";
  r.operation = op;
  r.kind = "time";
  r.published = published;
  r.unit = unit;
  r.source = kHaines;
  r.grade = "primary";
  r.model = model;
  r.errorPct = (model - published) / published * 100;
  r.note = note;
  return r;
}
}  // namespace

std::vector<LedgerRow> HostRows() {
  const testbed::HostProfile& hp = testbed::HostProfileNamed("hp-835");
  std::vector<LedgerRow> rows;
  for (const SpdTiming& h : kHainesHp835) {
    TraceStats tests;
    tests.tests[int(ShapeKind::kPolygon)] = uint64_t(h.polygonK * 1000);
    tests.tests[int(ShapeKind::kSphere)] = uint64_t(h.sphereK * 1000);
    tests.tests[int(ShapeKind::kCone)] = uint64_t(h.coneK * 1000);
    tests.boxTests = uint64_t(h.boxK * 1000);
    TraceStats rays;
    rays.rays[int(RayKind::kPrimary)] = uint64_t(kEyeRays);
    rays.rays[int(RayKind::kReflected)] = uint64_t(h.reflect);
    rays.rays[int(RayKind::kRefracted)] = uint64_t(h.refract);
    rays.rays[int(RayKind::kShadow)] = uint64_t(h.shadow);
    const double testSeconds = testbed::ModelHostTime(tests, hp).seconds;
    const double raySeconds = testbed::ModelHostTime(rays, hp).seconds;
    rows.push_back(HostTimeRow(
        fmt::format("SPD {} ray tracing (Haines' counts)", h.scene), h.seconds, "s",
        testSeconds + raySeconds,
        fmt::format("tests {:.0f} s + rays {:.0f} s on hp-835 (shading: no published count, "
                    "not priced)",
                    testSeconds, raySeconds)));
  }
  // One test of each kind Haines timed, in µs: ModelHostTime of a million tests, in seconds.
  TraceStats box, polygon;
  box.boxTests = 1000000;
  polygon.tests[int(ShapeKind::kPolygon)] = 1000000;
  rows.push_back(HostTimeRow("bounding box test (tetra)", kHainesBoxMicros, "us",
                             testbed::ModelHostTime(box, hp).seconds,
                             "the work table's boxTest on hp-835"));
  rows.push_back(HostTimeRow("polygon test (tetra)", kHainesPolygonMicros, "us",
                             testbed::ModelHostTime(polygon, hp).seconds,
                             "the work table's polygonTest on hp-835"));
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
  r.grade = "primary";  // the paper itself, read
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
  std::string s = "machine,operation,kind,published,unit,model,error_pct,holds,grade,source\n";
  for (const LedgerRow& r : rows)
    s += fmt::format("{},{},{},{:g},{},{:.6g},{:.4f},{},{},\"{}\"\n", r.machine, r.operation,
                     r.kind, r.published, r.unit, r.model, r.errorPct, r.holds ? "yes" : "no",
                     r.grade, r.source);
  return s;
}

namespace {
// docs/validation.md's fixed sections: why each row has its grade, and what the host rows price.
const char* const kGradesAndHostRows = R"(
## Grades

Each row's grade was decided from what its source string cites (the code's own record of
where a figure came from):

- **mpp, 8-bit add and multiply, 32-bit floating add and multiply: primary.** The source
  names the table of operation speeds in Batcher's paper itself (IEEE Trans. Computers
  C-29(9), 1980), and the profile's entries cite the paper's sections (100 ns cycle, 128x128
  PEs, 1024 bits each). No copy of the paper is in the repository: the grade rests on those
  citations.
- **mpp, 12-bit add and multiply: secondary.** These two figures are known to us only from a
  reproduction of Batcher's table, not from the paper read; the table says so beside their
  errors.
- **blitzen, both bounds: primary (the abstract).** The source names the abstract of Blevins et
  al. 1990: the authors' own words, though only the abstract was read.
- **paper (ufmg1992): primary.** The paper itself was read; its rows check its findings
  (orderings of Figs 5-12), not numbers.
- **hp-835: primary.** Haines' Standard Procedural Databases README v3.14 was read whole (its
  Timings and Database Analysis sections give every published count and time). The hp-835
  profile's ratings are a different matter: no published rating of the 835 could be read, so
  all are assumed (docs/testbed.md), a weakness of the model, not of the published figures.
- **pim-bitsimd-v-bank: derived.** PIMeval's BitSIMD-V table (libpimeval/src/
  pimPerfEnergyTables.cpp, read at its source) gives counts of row reads, row writes and logic
  ops, not cycles; the published figure is our arithmetic on them at PIMeval's own DDR4-3200
  timing. It is one model against another, never a measurement of a chip.

## Model rows (pim-bitsimd-v-bank)

Each row sets the engine's cycles of one operation (signed n-bit operands, the result in their
format; one virtual-PE layer) on the pim-bitsimd-v-bank profile against PIMeval's count for its
BitSIMD-V device at the same width, (row reads + row writes) x 74 tCK + logic ops x 4 tCK. The
profile's micro-op prices were fixed from the same PIMeval timing before these rows were
computed, so the rows compare the two schedules, op by op. Add, subtract, less-than and min
agree within 2 % (the engine's carry set and clear cost a few logic ops more). The multiply
is twice PIMeval's at every width, and the counts say why: at 8 bits PIMeval reads 72 rows and
writes 36, 2 reads and 1 write for each of the 36 bits of the low triangle of the 8x8 product
that an 8-bit result keeps (n(n+1)/2); the engine's schedule (docs/bitserial.md, Multiply)
computes all n^2 = 64 partial-sum bits of the square and fits the result after, each step
reading an operand row and the accumulator's row back (this device has no shift register:
`zephyr cycles --profile pim-bitsimd-v-bank --op mul --bits 8 --json` gives 72 operand reads,
72 accumulator reads, 64 accumulator writes, 8 result writes): 216 row accesses against 108.
A schedule that computes only the kept triangle would meet PIMeval's; the engine's is the
MPP's, whose table it reproduces (n^2 + 3n cycles).

## Host rows (hp-835)

Haines' README times the ray tracing of each SPD scene (512x512 pixels, 513x513 eye rays,
depth 5; the Ray-Tracing column, without input and setup) on an HP 9000/835 with his
tracer's counts of polygon, sphere, cylinder/cone and bounding-box tests (a Goldsmith-Salmon
hierarchy), and its Database Analysis gives each scene's reflected, refracted and shadow
rays. Each row prices exactly those counts with the work table on the `hp-835` profile
(`polygonTest`, `sphereTest`, `coneTest`, `boxTest`, `ray`) and sets the seconds against his.
Not priced, for want of a published count: shading, light evaluation, nearest-hit
bookkeeping, pixels and hierarchy traversal beyond its box tests; so the model is expected
below his time by their share. Also, the work table's polygon test assumes 4 edges, while
gears' faces have 144 vertices. The two per-test rows set the work table's price of one box
and one polygon test against the microseconds per test his tetra statistics give.
Nothing was tuned: the profile was fixed (and committed) before these rows were computed.

Our own render of each SPD scene priced on hp-835 (issue 43, item 1b) is not in the ledger
yet: it needs the SPD generators' default-size scenes, which are not part of this repository.
)";

// A figure in its unit: whole numbers from 100 up, two decimals below (µs per test).
std::string Figure(double v, const std::string& unit) {
  // Two calls, not one format chosen at run time: fmt checks each format string when compiled.
  return std::fabs(v) >= 100 ? fmt::format("{:.0f} {}", v, unit)
                              : fmt::format("{:.2f} {}", v, unit);
}
bool HasError(const LedgerRow& r) {
  return r.kind == "rate" || r.kind == "time" || r.kind == "model";
}
}  // namespace

std::string LedgerMarkdown(const std::vector<LedgerRow>& rows, const std::string& runsFile) {
  std::string s =
      "# The fidelity ledger\n\n"
      "Every published figure the model can be set against, with the model's value and its\n"
      "error. Written by `make validate` (`zephyr validate --runs " +
      runsFile +
      "`); do not edit by hand. Machine rows: the engine's cycles on the profile's file\n"
      "(bitserial/profiles/, docs/bitserial.md), rate = PEs × clock ÷ cycles. Host rows: the\n"
      "host work table (docs/testbed.md) pricing a publication's own counts on the host profile\n"
      "of the machine it was timed on, against its time (error = (model − published) ÷\n"
      "published). Paper rows: the paper's findings on the modelled 1992 seconds of the testbed\n"
      "sweep (docs/testbed.md), the margin the worst point of the sweep has (negative: the\n"
      "finding does not hold there). Each row's source is graded: primary (the publication\n"
      "itself read), secondary (a survey, a summary page or a reproduction), derived (our\n"
      "arithmetic on quoted figures); a secondary row says so beside its error.\n"
      "`make test` fails if any row's error grows past tools/validation_recorded.csv.\n\n"
      "| machine | operation | kind | published | model | error | holds | grade | source | how |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const LedgerRow& r : rows) {
    const bool check = r.kind == "check";
    const std::string error = HasError(r) ? fmt::format("{:+.2f} %", r.errorPct)
                                          : fmt::format("{:.1f} % short", r.errorPct);
    s += fmt::format("| {} | {} | {} | {} | {} | {}{} | {} | {} | {} | {} |\n", r.machine,
                     r.operation, r.kind, check ? "holds" : Figure(r.published, r.unit),
                     check ? fmt::format("{:+.1f} % margin", r.model) : Figure(r.model, r.unit),
                     error, r.grade == "secondary" ? " (secondary)" : "",
                     HasError(r) ? "" : (r.holds ? "yes" : "**no**"), r.grade, r.source, r.note);
  }
  // Per machine, in the order the table first names it: any machine name (a profile added
  // later gets its own line).
  struct Summary {
    int rows = 0, errorRows = 0, held = 0, judged = 0;
    double sum = 0, max = 0;
  };
  std::vector<std::string> order;
  std::map<std::string, Summary> perMachine;
  for (const LedgerRow& r : rows) {
    if (!perMachine.count(r.machine)) order.push_back(r.machine);
    Summary& m = perMachine[r.machine];
    ++m.rows;
    if (HasError(r)) {
      ++m.errorRows;
      m.sum += std::fabs(r.errorPct);
      m.max = std::max(m.max, std::fabs(r.errorPct));
    } else {
      ++m.judged;
      m.held += r.holds;
    }
  }
  s += "\n| machine | rows | rate/time/model rows | mean abs error | max abs error | bounds/checks "
       "held |\n|---|---|---|---|---|---|\n";
  for (const std::string& name : order) {
    const Summary& m = perMachine[name];
    s += fmt::format("| {} | {} | {} | {} | {} | {} |\n", name, m.rows, m.errorRows,
                     m.errorRows ? fmt::format("{:.2f} %", m.sum / m.errorRows) : "-",
                     m.errorRows ? fmt::format("{:.2f} %", m.max) : "-",
                     m.judged ? fmt::format("{} of {}", m.held, m.judged) : "-");
  }
  int bounds = 0, met = 0, checks = 0, held = 0;
  for (const LedgerRow& r : rows) {
    if (r.kind == "lower bound") ++bounds, met += r.holds;
    if (r.kind == "check") ++checks, held += r.holds;
  }
  s += fmt::format("\nBounds met: {} of {}. Paper findings holding: {} of {}.\n", met, bounds, held,
                   checks);
  s += "\n![model against published](results/validation.png)\n";
  s += kGradesAndHostRows;
  return s;
}

}  // namespace zephyr::ledger
