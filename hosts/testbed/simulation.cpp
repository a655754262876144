// hosts/testbed/simulation.cpp — the SimGrid glue (hosts/testbed/simulation.h): S4U calls in
// the zephyr-smpi build, nothing in the ordinary one.
#include "hosts/testbed/simulation.h"

#include "fixed/check.h"
#include "hosts/testbed/host_profile.h"
#include "hosts/testbed/testbed.h"

#ifdef ZEPHYR_SMPI
#include <mpi.h>
#include <simgrid/plugins/load.h>

#include <simgrid/s4u.hpp>
#include <xbt/config.hpp>
#endif

namespace zephyr::testbed {

namespace {
// This rank's charged host seconds (ChargeHostWork), and the part ChargeArrayCycles charged
// (the uncertain pixels recomputed): under SMPI every rank has its own copy of globals.
double charged = 0, passHost = 0;
}  // namespace

double ChargedHostSeconds() { return charged; }
double ChargedPassHostSeconds() { return passHost; }

#ifdef ZEPHYR_SMPI

bool Simulated() { return true; }

double SimulatedNow() { return simgrid::s4u::Engine::get_clock(); }

std::string SimulatedPlatformName() {
  return simgrid::s4u::Engine::get_instance()->get_netzone_root()->get_name();
}

std::string SimulatedArrayProfile() {
  for (simgrid::s4u::Host* h : simgrid::s4u::Engine::get_instance()->get_all_hosts()) {
    const char* role = h->get_property("zephyr:role");
    const char* profile = h->get_property("zephyr:array-profile");
    if (role && std::string(role) == "array" && profile) return profile;
  }
  return "";
}

namespace {
const HostProfile* ProfileOf(simgrid::s4u::Host* h) {
  const char* name = h->get_property("zephyr:profile");
  return name ? &HostProfileNamed(name) : nullptr;
}
}  // namespace

nlohmann::json SimulatedHost() {
  simgrid::s4u::Host* h = simgrid::s4u::this_actor::get_host();
  const HostProfile* p = ProfileOf(h);
  return {{"host", h->get_name()},
          {"speedFlops", h->get_speed()},
          {"profile", p ? p->name : std::string("(none: flops + instructions at the host speed)")}};
}

double ChargeHostWork(const TraceStats& work) {
  simgrid::s4u::Host* h = simgrid::s4u::this_actor::get_host();
  const double start = SimulatedNow();
  // With a profile: its modelled seconds, as flops at this host's speed (so the charge is
  // exactly those seconds on an unshared host). Without: every operation as one flop.
  double flops;
  if (const HostProfile* p = ProfileOf(h)) {
    flops = ModelHostTime(work, *p).seconds * h->get_speed();
  } else {
    const HostTime t = ModelHostTime(work, HostProfileNamed("sparcstation2"));
    flops = t.flops + t.instructions;
  }
  if (flops > 0) smpi_execute_flops(flops);
  charged += SimulatedNow() - start;
  return SimulatedNow() - start;
}

namespace {
bool linkLoadPlugin() {
  const std::string plugin = simgrid::config::get_value<std::string>("plugin");
  return plugin.find("link_load") != std::string::npos;
}
bool linksTracked = false;
}  // namespace

void StartLinkAccounting() {
  if (!linkLoadPlugin()) return;
  for (simgrid::s4u::Link* link : simgrid::s4u::Engine::get_instance()->get_all_links())
    sg_link_load_track(link);
  linksTracked = true;
}

nlohmann::json LinkLoads(double now) {
  nlohmann::json links = nlohmann::json::array();
  if (!linksTracked) return links;
  for (simgrid::s4u::Link* link : simgrid::s4u::Engine::get_instance()->get_all_links()) {
    const double bytes = sg_link_get_cum_load(link);
    // SimGrid keeps bandwidths in bytes per second.
    links.push_back({{"link", link->get_name()},
                     {"bytes", bytes},
                     {"bandwidthBytesPerSecond", link->get_bandwidth()},
                     {"busyFraction", now > 0 ? bytes / link->get_bandwidth() / now : 0.0}});
  }
  return links;
}

double ChargeArrayCycles(const bitserial::CycleReport& cycles,
                         const bitserial::CycleReport* refineCycles,
                         const TraceStats& recomputeWork, const std::string& method) {
  const double start = SimulatedNow();
  simgrid::s4u::Host* self = simgrid::s4u::this_actor::get_host();
  const auto arrays =
      simgrid::s4u::Engine::get_instance()->get_filtered_hosts([](simgrid::s4u::Host* h) {
        const char* role = h->get_property("zephyr:role");
        return role && std::string(role) == "array";
      });
  if (arrays.size() != 1)
    throw UserError("the platform has " + std::to_string(arrays.size()) +
                    " hosts with zephyr:role=array; the " + method +
                    " method needs exactly one "
                    "(docs/testbed.md)");
  const ArraySplit a = SplitArrayCycles(cycles, refineCycles);
  // The array computes at its clock (the platform gives its speed in cycles per second).
  simgrid::s4u::this_actor::exec_init(a.arrayCycles)->set_host(arrays[0])->wait();
  if (a.linkBytes > 0) simgrid::s4u::Comm::sendto(arrays[0], self, uint64_t(a.linkBytes));
  passHost += ChargeHostWork(recomputeWork);
  return SimulatedNow() - start;
}

#else

bool Simulated() { return false; }
double SimulatedNow() { return 0; }
std::string SimulatedPlatformName() { return ""; }
std::string SimulatedArrayProfile() { return ""; }
nlohmann::json SimulatedHost() { return nlohmann::json::object(); }
double ChargeHostWork(const TraceStats&) { return 0; }
double ChargeArrayCycles(const bitserial::CycleReport&, const bitserial::CycleReport*,
                         const TraceStats&, const std::string&) {
  return 0;
}
void StartLinkAccounting() {}
nlohmann::json LinkLoads(double) { return nlohmann::json::array(); }

#endif

}  // namespace zephyr::testbed
