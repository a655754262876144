// hosts/testbed/testbed.h — the paper's 1992 testbed, modelled (§5–6.1; docs/testbed.md).
//
// A testbed names the machines of a run: the host/parent and the children (host profiles,
// hosts/testbed/host_profile.h), the SIMD array (a bitserial machine profile) and the
// network (a SimGrid platform: one shared Ethernet, the SCSI link to the array).
//
//   * seq and simd need no network: `zephyr render --testbed ufmg1992` adds report
//     "testbed" with the modelled seconds from the counted work (AddModelledTime).
//   * dist and hetero run unmodified under SimGrid's SMPI (build/bin/zephyr-smpi under
//     smpirun, `make smpi`): each child charges its counted work to its simulated host
//     (ChargeHostWork), the parent charges the array pass (ChargeArrayPass); the report's
//     modelled seconds are SimGrid's clock. In the ordinary build these calls do nothing.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hosts/scene/scene.h"
#include "hosts/testbed/host_profile.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace simd {
struct PrimaryPass;
}
}  // namespace zephyr

namespace zephyr::testbed {

struct Testbed {
  std::string name;           // "ufmg1992"
  std::string description;
  std::string parentProfile;  // host profile of the host/parent (seq, simd, parent of dist/hetero)
  std::string childProfile;   // host profile of every child
  std::string arrayProfile;   // bitserial machine profile of the SIMD array
  Sourced ethernetBandwidth;  // bit/s, one medium shared by every host
  Sourced ethernetLatency;    // s, per message
  Sourced scsiBandwidth;      // byte/s, host <-> array
  nlohmann::json Json() const;
};

// The named testbeds ("ufmg1992"); UserError for an unknown name, listing the known ones.
const Testbed& TestbedNamed(const std::string& name);
std::vector<std::string> TestbedNames();

// A SimGrid platform (XML v4.1) of the testbed with `children` child hosts: "parent" (the
// parent's profile), "zephyr" (the array, speed = its clock), "child-1".."child-K", one
// SHARED Ethernet link on every parent-child route, the SCSI link parent-zephyr. Hosts carry
// "zephyr:profile" and "zephyr:role" properties. UserError for children outside
// 1..kMaxPlatformChildren.
// With hostOps > 0 the parent and the children have that speed and no profile: each counted
// operation (work-table flop or instruction) costs 1/hostOps seconds (a calibrated this-host).
inline constexpr int kMaxPlatformChildren = 4096;
std::string PlatformXml(const Testbed& bed, int children, double hostOps = 0);

// The this-host profile: from the report of a seq render measured on this host, its counted
// operations (the work table's flops + instructions) over the render phase's seconds:
// {"profile": "this-host", "operationsPerSecond", "operations", "flops", "instructions",
// "measuredSeconds", "source"}. One rate for both kinds (an assumption: one measurement
// cannot separate them). UserError (naming `file`) for a report of another method or
// without counts or a positive render time.
nlohmann::json CalibrateThisHost(const nlohmann::json& report, const std::string& file);
// smpirun's hostfile for it: rank 0 on the parent, rank i on child-i.
std::string Hostfile(int children);

// True in the build made with smpicxx (zephyr-smpi), where time is SimGrid's.
bool Simulated();

// Modelled seconds on the testbed `testbedName` ("" = none: does nothing) of a finished
// render of `scene` by `method`, from the counts in its report (the method's TraceStats at
// the top level; simd's cycle report under "simd"). Adds report["testbed"]:
// {"testbed", "modelledSeconds", "host": HostTime, "array": {...}}. For dist/hetero it
// requires the simulated build and reports SimGrid's clock (UserError otherwise), with what
// the simulation measured: "parent" (its charged host work and array pass, seconds),
// "children" (per child: simulated busy and idle seconds) and "links" (per platform link:
// bytes carried, from SimGrid's link_load plugin when simrun.sh enabled it). seq and simd
// under simulation (`simrun.sh --children 0 --platform FILE`) charge their counted work to
// the rank's host and simd's array cycles to the platform's array host (ChargeArrayCycles),
// and report SimGrid's seconds for them. UserError for an unknown testbed (naming simrun.sh
// when it is a file) or a method that counts no work.
// Everything AddModelledTime will refuse that the command line alone decides, checked before
// any work: an unknown testbed, dist/hetero outside SimGrid, a --machine other than the
// testbed's array. `arrayProfile` is the machine profile the SIMD pass would use. No-op
// when `testbedName` is empty.
void CheckModelledTimeRequest(const std::string& testbedName, const std::string& method,
                              const std::string& arrayProfile);

void AddModelledTime(const std::string& testbedName, const std::string& method,
                     const Scene& scene, nlohmann::json& report);

// Under simulation: charges counted host work to this rank's simulated host (its profile
// is the platform host's "zephyr:profile" property; without one, the work's flops plus
// instructions at the host's speed). Returns the simulated seconds charged (0 otherwise).
double ChargeHostWork(const TraceStats& work);

// Under simulation, at the parent: the SIMD pass's array cycles (its first pass and, when
// one ran, its refine pass) on the platform's array host ("zephyr:role" = "array"), the
// matrix over the SCSI link between them, and the host's share of the pass (uncertain
// pixels recomputed) on the parent. Returns the simulated seconds it took (0 when not
// simulated).
double ChargeArrayPass(const simd::PrimaryPass& pass, const Scene& scene);
// The same from the passes' cycle reports (JSON, as `render --report` writes them under
// "simd": "cycles", and "refine"."cycles" or null when no refine pass ran) and the count of
// uncertain pixels recomputed on the host; `method` names the caller in the UserError for a
// platform without exactly one array host.
double ChargeArrayCycles(const nlohmann::json& cycles, const nlohmann::json& refineCycles,
                         uint64_t recomputedPixels, const Scene& scene, const std::string& method);

// Under simulation, at the parent before its first message: starts counting the bytes every
// platform link carries (SimGrid's link_load plugin, `--cfg=plugin:link_load`, which
// tools/testbed/simrun.sh sets; without it nothing is counted). Does nothing otherwise.
void StartLinkAccounting();

// The simulated seconds since the simulation started (0 when not simulated).
double SimulatedNow();

// Under simulation, a JSON object with this rank's host name, its profile and speed.
nlohmann::json SimulatedHost();

}  // namespace zephyr::testbed
