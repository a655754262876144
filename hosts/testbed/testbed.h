// hosts/testbed/testbed.h — the paper's 1992 testbed, modelled (§5–6.1; docs/testbed.md), and
// present-day ones for its future work (§8; docs/present-day.md).
//
// A testbed names the machines of a run: the host/parent and the children (host profiles,
// hosts/testbed/host_profile.h), the SIMD array (a bitserial machine profile) and the
// network (a SimGrid platform: a shared or a switched Ethernet, the link to the array).
//
//   * seq and simd need no network: `zephyr render --testbed ufmg1992` adds report
//     "testbed" with the modelled seconds from the counted work (ModelTime).
//   * dist and hetero run unmodified under SimGrid's SMPI (build/bin/zephyr-smpi under
//     smpirun, `make smpi`): each child charges its counted work to its simulated host,
//     the parent charges the array pass (hosts/testbed/simulation.h); the report's
//     modelled seconds are SimGrid's clock. In the ordinary build those calls do nothing.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/report.h"
#include "hosts/scene/scene.h"
#include "hosts/testbed/host_profile.h"
#include "hosts/trace/tracer.h"

namespace zephyr::testbed {

// How the hosts reach one another over the Ethernet.
enum class EthernetTopology {
  kShared,    // one medium every station's traffic shares (10BASE coax: one SimGrid link)
  kSwitched,  // each host its own port to a switch whose backplane never limits (switched
              // 10/25 GbE): the parent's port carries all the farm's traffic
};

struct Testbed {
  std::string name;  // "ufmg1992", "today-zephyr", "today-pim"
  std::string description;
  std::string parentProfile;  // host profile of the host/parent (seq, simd, parent of dist/hetero)
  std::string childProfile;   // host profile of every child
  std::string arrayProfile;   // bitserial machine profile of the SIMD array (a built-in name)
  Sourced ethernetBandwidth;  // bit/s: the shared medium's, or each switch port's
  Sourced ethernetLatency;    // s, one way per message (over both ports when switched)
  EthernetTopology ethernetTopology = EthernetTopology::kShared;
  std::string ethernetTopologySource;  // why this topology (a citation or "assumed: ...")
  std::string arrayLink;               // the host <-> array link's name: "scsi", "memory-bus"
  Sourced arrayLinkBandwidth;          // byte/s, host <-> array
  // s of simulated time each MPI_Test and MPI_Iprobe costs its caller (SimGrid's smpi/test and
  // smpi/iprobe, written into the platform file; ufmg1992 keeps SimGrid's default, 1e-4 s).
  Sourced mpiPollSeconds;
  nlohmann::json Json() const;
};

// The named testbeds ("ufmg1992"); UserError for an unknown name, listing the known ones.
const Testbed& TestbedNamed(const std::string& name);
std::vector<std::string> TestbedNames();
// The array profile of the named testbed `name`; nothing when `name` names no built-in
// testbed (a platform file, or a mistake that ModelTime reports).
std::optional<std::string> TestbedArrayProfile(const std::string& name);

// A SimGrid platform (XML v4.1) of the testbed with `children` child hosts: "parent" (the
// parent's profile), "zephyr" (the array, speed = its clock), "child-1".."child-K"; the
// Ethernet as one SHARED link "ethernet" on every parent-child route (kShared), or (kSwitched)
// a port link per host, "ethernet" the parent's and "ethernet-child-I" each child's, a route
// crossing the parent's port and the child's, each port half the one-way latency; the array
// link (bed.arrayLink) parent-zephyr. Hosts carry "zephyr:profile" and "zephyr:role"
// properties. UserError for children outside
// 1..kMaxPlatformChildren.
// With hostOps > 0 the parent and the children have that speed and no profile: each counted
// operation (work-table flop or instruction) costs 1/hostOps seconds (a calibrated this-host).
// With arrayClockHz > 0 the array host runs at that clock instead of its profile's (what-if).
inline constexpr int kMaxPlatformChildren = 4096;
std::string PlatformXml(const Testbed& bed, int children, double hostOps = 0,
                        double arrayClockHz = 0);

// The this-host profile: from the report of a seq render measured on this host, its counted
// operations (the work table's flops + instructions) over the render phase's seconds:
// {"profile": "this-host", "operationsPerSecond", "operations", "flops", "instructions",
// "measuredSeconds", "source"}. One rate for both kinds (an assumption: one measurement
// cannot separate them). UserError (naming `file`) for a report of another method or
// without counts or a positive render time.
nlohmann::json CalibrateThisHost(const nlohmann::json& report, const std::string& file);
// smpirun's hostfile for it: rank 0 on the parent, rank i on child-i.
std::string Hostfile(int children);

// The SIMD pass's cycles split into the array's own and the host link's (the cycle reports'
// "host" class: the matrix moving over the testbed's array link, SCSI in 1992, the memory bus
// on today-pim), summed over the array passes that ran: the
// first pass's report, and the refine pass's when one ran (null otherwise). Cycles at the
// profile's clock (Hz); bytes: one hostPlane moves one bit of every physical PE.
struct ArraySplit {
  double arraySeconds = 0, linkSeconds = 0, linkBytes = 0, clockHz = 0, arrayCycles = 0;
  double refineCycles = 0;  // the refine pass's share of arrayCycles + its host class
};
ArraySplit SplitArrayCycles(const bitserial::CycleReport& first,
                            const bitserial::CycleReport* refine);

// The farm's figures the testbed needs (dist, hetero under simulation): per child its rank,
// host and the simulated seconds its charged work took (none when its stats did not say).
struct FarmTimes {
  struct Child {
    int rank = 0;
    std::string host;
    std::optional<double> busySeconds{};
  };
  std::vector<Child> children;
  double parentPassSeconds = 0;  // the array pass at the parent (hetero; 0 for dist)
};

// A finished render's counted work, for the testbed to price. The testbed knows no method:
// it prices what was counted.
struct CountedWork {
  const TraceStats* host = nullptr;  // the host's counted work (seq; simd's shading); null: none
  // The array (simd, array, hetero): the first pass's cycle report (with all rays on the array,
  // the sum of it and every wavefront bounce's), the refine pass's (null when none ran), and the
  // uncertain pixels the host recomputed in double.
  const bitserial::CycleReport* arrayCycles = nullptr;
  const bitserial::CycleReport* refineCycles = nullptr;
  uint64_t recomputedPixels = 0;
  // What the recompute counted (simd::PrimaryPass::recomputeWork), priced instead of
  // recomputedPixels' closed form when given (with --accel bvh the two differ).
  const TraceStats* recomputeWork = nullptr;
  const FarmTimes* farm = nullptr;  // the frame farm (dist, hetero); null: one process
};

// Modelled seconds of a render on a testbed (the report's "testbed" section). Outside
// simulation (one process: seq, simd) from the work table and the array's cycles; under
// simulation SimGrid's clock and what the simulation measured.
struct ModelledTime {
  std::string testbed;  // the testbed's name
  double modelledSeconds = 0;
  // Outside simulation: the testbed, the host's profile and modelled time; the array's share
  // when the SIMD pass ran.
  const Testbed* bed = nullptr;
  const HostProfile* hostProfile = nullptr;
  std::optional<HostTime> host;
  struct ArrayShare {
    std::string profile;
    ArraySplit split;
  };
  std::optional<ArrayShare> array;
  // Under simulation: what the clock measured, this rank's simulated host (SimulatedHost()).
  std::string clock;
  nlohmann::json simulatedHost;
  // seq/simd under simulation: the host's charged seconds and its events, the array's.
  std::optional<double> simulatedHostSeconds, simulatedArraySeconds;
  TraceStats simulatedEvents;
  // dist/hetero under simulation: the parent's split, the children, the links' bytes.
  struct FarmSplit {
    double arrayPassSeconds = 0, hostWorkSeconds = 0, waitingSeconds = 0;
    struct Child {
      int rank = 0;
      std::string host;
      std::optional<double> busySeconds{}, idleSeconds{};
    };
    std::vector<Child> children;
    nlohmann::json links;  // SimGrid's link_load figures per link (LinkLoads)
  };
  std::optional<FarmSplit> farm;
  nlohmann::json Json() const;  // the report's "testbed" section (docs/testbed.md)
  // The array's busy share of the modelled time, as the CM-2's CM:TIME printed "CM active X %
  // of elapsed": its own cycles' seconds (not the host link's) over modelledSeconds; under
  // simulation the array pass's charged seconds (hetero: the parent's array pass). Nothing
  // when no array ran or the modelled time is 0.
  std::optional<double> ArrayActiveShare() const;
};

// What a render asks to be priced on, as the command line says it (--testbed,
// --also-testbed), checked once, before any work and on every rank of a farmed render, by
// CheckPricingRequest.
struct PricingRequest {
  std::string testbed;                    // "" = none (then no more testbeds either)
  std::vector<std::string> alsoTestbeds;  // more testbeds the same counted work is priced on
  std::string method;                     // only names it in messages
  bool farmed = false;     // dist, hetero: timed by a simulation of one testbed's network
  bool usesArray = false;  // every testbed's array must be `arrayProfile`
  std::string arrayProfile;  // the machine profile the SIMD pass would use
};

// Everything ModelTime will refuse that the command line alone decides: an unknown testbed,
// a farmed method outside SimGrid, a --machine other than a testbed's array; more testbeds
// without a first one, for a farmed or simulated run (one testbed a run), named twice, or with
// another array than the first's. UserError naming the testbed; nothing when `testbed` is "".
void CheckPricingRequest(const PricingRequest& request);

// The modelled seconds on the testbed `testbedName` ("" = none: nullopt) of the counted work
// of a finished render of `scene`. A farmed render (work.farm) needs the simulated build
// and reports SimGrid's clock (UserError otherwise); seq and simd under simulation
// (`simrun.sh --children 0 --platform FILE`) charge their counted work to the rank's host
// and the array's cycles to the platform's array host (ChargeArrayCycles). UserError for an
// unknown testbed (naming simrun.sh when it is a file), an array of another profile than
// the testbed's, or work that counts nothing.
std::optional<ModelledTime> ModelTime(const std::string& testbedName, const CountedWork& work,
                                      const Scene& scene);

}  // namespace zephyr::testbed
