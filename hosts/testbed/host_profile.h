// hosts/testbed/host_profile.h — host profiles: counted tracer work turned into modelled
// seconds on a named workstation: the paper's 1992 ones (§5–6.1) or a present-day core
// (docs/testbed.md, docs/present-day.md).
//
// Two tables, both data:
//   * the WORK table: what one counted event (a ray–sphere test, a shaded point, a light
//     sample, a pixel, ...) costs in floating-point operations and other instructions. It is
//     a property of the code in hosts/trace/ (counted from it by hand), not of a machine.
//   * a HOST PROFILE: a machine's published rates (clock, MIPS, double-precision Linpack
//     MFLOPS, SPEC92), each entry with its value, unit and source ("assumed: ..." where no
//     source gives one).
// Modelled seconds = Σ count × (flops / (MFLOPS·10⁶) + instructions / (MIPS·10⁶)): an
// additive model (FP work at the Linpack rate, the rest at the MIPS rate). It depends on
// the counts only, so the same scene gives the same seconds on any machine.
//
//   const HostProfile& ss2 = HostProfileNamed("sparcstation2");
//   HostTime t = ModelHostTime(stats, ss2);   // t.seconds, t.Json()
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "hosts/trace/tracer.h"

namespace zephyr::testbed {

// One entry of a profile or of the work table: a number with its unit and where it comes
// from (a citation, or "assumed: why").
struct Sourced {
  double value = 0;
  std::string unit;
  std::string source;
  nlohmann::json Json() const;  // {"value", "unit", "source"}
};

struct HostProfile {
  std::string name;             // "sparcstation2", "sparcstation-slc", "today-calibrated", ...
  std::string description;      // "Sun SPARCstation 2 (Sun 4/75), the paper's host and parent"
  Sourced clock;                // Hz (reported; not used by the model)
  Sourced mips;                 // million instructions per second (used: non-FP work)
  Sourced mflops;               // double-precision Linpack 100×100, MFLOPS (used: FP work)
  Sourced specint92, specfp92;  // SPEC ratios (reported; 0 with a source saying why)
  nlohmann::json Json() const;
  std::string Table() const;  // one line per entry: name, value, unit, source
};

// The known profiles; HostProfileNamed throws UserError for an unknown name, listing them.
const HostProfile& HostProfileNamed(const std::string& name);
std::vector<std::string> HostProfileNames();

// The counted events of the work table, in TraceStats terms.
enum class WorkEvent : int {
  kSphereTest,
  kConeTest,
  kPolygonTest,  // one ray–primitive test (TraceStats::tests)
  kRay,          // one ray set up (any kind: primary, shadow, reflected, refracted)
  kHit,          // a nearest hit found and recorded
  kShade,        // one surface point shaded (point, normal, recursion set-up)
  kLightSample,  // one light evaluated at a shaded point (direction, diffuse, highlight)
  kPixel,        // one pixel written
  // --accel bvh (TraceStats::nodeVisits, boxTests, bvhBinned, bvhNodes):
  kNodeVisit,  // one hierarchy node taken from the walk's stack and examined
  kBoxTest,    // one ray–box slab test
  kBvhBin,     // the build: one primitive binned on three axes
  kBvhNode,    // the build: one node made (its box, its SAH sweep over the bins)
  kCount
};
inline constexpr int kWorkEvents = int(WorkEvent::kCount);
const char* WorkEventName(WorkEvent e);  // "sphereTest", ...

struct WorkCost {
  double flops = 0;         // floating-point operations per event
  double instructions = 0;  // other instructions per event (loads, loop, branches, calls)
  std::string source;       // how the numbers were counted
};
// The work table (counted from hosts/trace/tracer.cpp, prepared.h, sphere_kernels.cpp and, for
// the hierarchy's events, hosts/trace/bvh_walk.h and bvh.cpp).
const WorkCost& CostOf(WorkEvent e);

// The events behind a TraceStats: count per event, in WorkEvent order.
std::vector<double> EventCounts(const TraceStats& stats);

// Modelled time of counted work on one profile.
struct HostTime {
  std::string profile;
  double flops = 0, instructions = 0;  // totals over all events
  double seconds = 0;                  // flops/MFLOPS + instructions/MIPS
  std::vector<double> counts;          // per event, in WorkEvent order
  std::vector<double> eventSeconds;    // per event: count × (flops/MFLOPS + instructions/MIPS), s
  // {"profile", "flops", "instructions", "seconds", "events": {name: {"count", "flops",
  // "instructions", "seconds"}}}
  nlohmann::json Json() const;
};
HostTime ModelHostTime(const TraceStats& stats, const HostProfile& profile);

// The host work of recomputing `pixels` primary rays in double against every object of the
// scene (the SIMD pass's uncertain pixels): one primary ray and one test per object each.
TraceStats RecomputeWork(uint64_t pixels, const Scene& scene);
// The same from what the recompute counted (simd::PrimaryPass::recomputeWork): its rays,
// tests, node visits, box tests and build; its hits are not priced (the closed form above
// never priced them: both give the same for an exhaustive recompute).
TraceStats RecomputeWork(const TraceStats& counted);

}  // namespace zephyr::testbed
