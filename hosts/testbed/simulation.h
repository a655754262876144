// hosts/testbed/simulation.h — the SimGrid glue (docs/testbed.md): charging counted work and
// the array's cycles to the simulated platform's hosts, and reading its clock and links. In
// the build made with smpicxx (zephyr-smpi, -DZEPHYR_SMPI) these talk to SimGrid's S4U; in
// the ordinary build they do nothing (Simulated() is false, every charge returns 0).
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "bitserial/report.h"
#include "hosts/scene/scene.h"
#include "hosts/trace/tracer.h"

namespace zephyr::testbed {

// True in the build made with smpicxx (zephyr-smpi), where time is SimGrid's.
bool Simulated();

// Under simulation: charges counted host work to this rank's simulated host (its profile
// is the platform host's "zephyr:profile" property; without one, the work's flops plus
// instructions at the host's speed). Returns the simulated seconds charged (0 otherwise).
double ChargeHostWork(const TraceStats& work);

// Under simulation, at the parent: the SIMD pass's array cycles (the first pass's report
// and, when one ran, the refine pass's; null otherwise) on the platform's array host
// ("zephyr:role" = "array"), the matrix over the SCSI link between them, and the host's
// share of the pass (`recomputeWork`: the uncertain pixels recomputed in double, as
// testbed::RecomputeWork prices them) on this host. `method` names the caller in the UserError for
// a platform without exactly one array host. Returns the simulated seconds it took (0 when not
// simulated).
double ChargeArrayCycles(const bitserial::CycleReport& cycles,
                         const bitserial::CycleReport* refineCycles,
                         const TraceStats& recomputeWork, const std::string& method);

// This rank's simulated seconds charged so far: all host work (ChargeHostWork), and the part
// ChargeArrayCycles charged (the uncertain pixels recomputed). 0 outside simulation.
double ChargedHostSeconds();
double ChargedPassHostSeconds();

// Under simulation, at the parent before its first message: starts counting the bytes every
// platform link carries (SimGrid's link_load plugin, `--cfg=plugin:link_load`, which
// tools/testbed/simrun.sh sets; without it nothing is counted). Does nothing otherwise.
void StartLinkAccounting();

// Per platform link: {"link", "bytes", "bandwidthBytesPerSecond", "busyFraction"} over `now`
// simulated seconds (empty when not counted).
nlohmann::json LinkLoads(double now);

// Under simulation, the platform's root zone's name (a testbed's platform names it after the
// testbed: PlatformXml) and the machine profile its array host declares
// ("zephyr:array-profile"); empty when not simulated or not declared.
std::string SimulatedPlatformName();
std::string SimulatedArrayProfile();

// The simulated seconds since the simulation started (0 when not simulated).
double SimulatedNow();

// Under simulation, a JSON object with this rank's host name, its profile and speed.
nlohmann::json SimulatedHost();

}  // namespace zephyr::testbed
