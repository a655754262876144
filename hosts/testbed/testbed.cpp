#include "hosts/testbed/testbed.h"

#include <cstdio>
#include <filesystem>
#include <map>

#include "bitserial/profile.h"
#include "fixed/check.h"
#include "hosts/simd/pass.h"

#ifdef ZEPHYR_SMPI
#include <mpi.h>
#include <simgrid/plugins/load.h>
#include <simgrid/s4u.hpp>
#include <xbt/config.hpp>
#endif

namespace zephyr::testbed {

namespace {

const std::map<std::string, Testbed>& Testbeds() {
  static const std::map<std::string, Testbed> testbeds = {
      {"ufmg1992",
       {"ufmg1992",
        "the paper's runs (§6.1): a SPARCstation 2 host/parent with the Zephyr on SCSI, "
        "SPARCstation SLC children, the department's Ethernet under PVM",
        "sparcstation2", "sparcstation-slc", "wavetracer",
        {10e6, "bit/s", "assumed: the SPARCstations' built-in 10 Mbit/s Ethernet (10BASE), one "
                        "medium shared by every station"},
        {1e-3, "s", "assumed: per-message latency of PVM 3 over Ethernet of the order of a "
                    "millisecond (daemon-routed UDP)"},
        {5e6, "byte/s", "assumed: SCSI-1 synchronous at 5 MB/s, the same figure as the "
                        "wavetracer profile's hostPlane cost"}}},
  };
  return testbeds;
}

// The SIMD pass's modelled seconds split into the array's own cycles and the host link
// (the cycle report's "host" class: the matrix moving over SCSI), summed over the array
// passes that ran: the first, and the refine pass when one ran (`refine` is null otherwise).
struct ArraySplit {
  double arraySeconds = 0, scsiSeconds = 0, scsiBytes = 0, clockHz = 0, arrayCycles = 0;
  double refineCycles = 0;  // the refine pass's share of arrayCycles + its host class
};
ArraySplit SplitPass(const nlohmann::json& cycles, const nlohmann::json& refine) {
  ArraySplit a;
  const bitserial::MachineProfile profile = bitserial::Profile(cycles.at("profile").get<std::string>());
  a.clockHz = cycles.at("clockHz").get<double>();
  double host = 0;
  for (const nlohmann::json* pass : {&cycles, refine.is_null() ? nullptr : &refine}) {
    if (!pass) continue;
    ZEPHYR_CHECK(pass->at("clockHz").get<double>() == a.clockHz);
    const double passHost = pass->at("byClass").at("host").get<double>();
    a.arrayCycles += pass->at("totalCycles").get<double>() - passHost;
    host += passHost;
    if (pass == &refine) a.refineCycles = pass->at("totalCycles").get<double>();
  }
  a.arraySeconds = a.arrayCycles / a.clockHz;
  a.scsiSeconds = host / a.clockHz;
  // One hostPlane moves one bit of every physical PE.
  const double planeCycles = profile.Cost(bitserial::MicroOp::HostPlane);
  a.scsiBytes = planeCycles > 0 ? host / planeCycles * profile.physicalPes / 8 : 0;
  return a;
}

// The refine pass's cycle report in a SIMD report's "simd" object (null when none ran).
nlohmann::json RefineCycles(const nlohmann::json& pass) {
  return pass.contains("refine") ? pass.at("refine").at("cycles") : nlohmann::json();
}

// This rank's charged host seconds (ChargeHostWork), and the part ChargeArrayPass charged
// (the uncertain pixels recomputed): under SMPI every rank has its own copy of globals.
double charged = 0, passHost = 0;
double ChargedSeconds() { return charged; }
double PassHostSeconds() { return passHost; }
nlohmann::json LinkBytes(double now);

}  // namespace

nlohmann::json Testbed::Json() const {
  return {{"name", name},
          {"description", description},
          {"parentProfile", parentProfile},
          {"childProfile", childProfile},
          {"arrayProfile", arrayProfile},
          {"ethernetBandwidth", ethernetBandwidth.Json()},
          {"ethernetLatency", ethernetLatency.Json()},
          {"scsiBandwidth", scsiBandwidth.Json()}};
}

const Testbed& TestbedNamed(const std::string& name) {
  auto it = Testbeds().find(name);
  if (it == Testbeds().end()) {
    std::string known;
    for (const auto& n : TestbedNames()) known += (known.empty() ? "" : ", ") + n;
    if (std::filesystem::is_regular_file(name))
      throw UserError("--testbed " + name + ": a platform file is simulated — run the render under "
                      "`tools/testbed/simrun.sh --children K --platform " + name +
                      " -- render ...` (K = 0 for seq and simd; docs/testbed.md)");
    throw UserError("--testbed: unknown testbed '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

std::vector<std::string> TestbedNames() {
  std::vector<std::string> names;
  for (const auto& [name, t] : Testbeds()) names.push_back(name);
  return names;
}

void CheckModelledTimeRequest(const std::string& testbedName, const std::string& method,
                              const std::string& arrayProfile) {
  if (testbedName.empty()) return;
  if (method == "dist" || method == "hetero") {
    if (!Simulated())
      throw UserError("--testbed with --method " + method +
                      " runs on a simulated network: build/bin/zephyr-smpi under smpirun "
                      "(`make smpi`; docs/testbed.md)");
    return;
  }
  if (Simulated()) return;  // the platform file names the hosts
  const Testbed& bed = TestbedNamed(testbedName);
  if (method == "simd" && arrayProfile != bed.arrayProfile)
    throw UserError("--testbed " + bed.name + ": its array is '" + bed.arrayProfile +
                    "', but --machine chose '" + arrayProfile + "'");
}

void AddModelledTime(const std::string& testbedName, const std::string& method,
                     const Scene& scene, nlohmann::json& r) {
  if (testbedName.empty()) return;
  nlohmann::json t;
  if (method == "dist" || method == "hetero") {
    if (!Simulated())
      throw UserError("--testbed with --method " + method +
                      " runs on a simulated network: build/bin/zephyr-smpi under smpirun "
                      "(`make smpi`; docs/testbed.md)");
    t["testbed"] = testbedName;
    const double now = SimulatedNow();
    t["modelledSeconds"] = now;
    t["clock"] = "SimGrid (simulated seconds from MPI start to the finished image at the parent)";
    const double pass = r.at("distributed").at("time").value("parentPassSeconds", 0.0);
    const double hostWork = ChargedSeconds() - (method == "hetero" ? PassHostSeconds() : 0);
    t["parent"] = SimulatedHost();
    t["parent"]["arrayPassSeconds"] = method == "hetero" ? pass : 0.0;
    t["parent"]["hostWorkSeconds"] = hostWork;
    t["parent"]["hostWorkSource"] =
        "pixels packed into slices and pasted from results (one work-table pixel each), "
        "degenerate frames shaded; the array pass apart";
    t["parent"]["waitingSeconds"] = now - hostWork - (method == "hetero" ? pass : 0.0);
    nlohmann::json children = nlohmann::json::array();
    for (const auto& c : r.at("distributed").at("perChild")) {
      nlohmann::json j = {{"rank", c.at("rank")}, {"host", c.at("host")}};
      if (c.contains("work") && c.at("work").contains("testbed")) {
        const auto& s = c.at("work").at("testbed");
        j["busySeconds"] = s.at("busySeconds");
        j["idleSeconds"] = now - s.at("busySeconds").get<double>();
      }
      children.push_back(j);
    }
    t["children"] = children;
    t["childrenIdleSource"] = "modelledSeconds minus the child's charged work";
    t["links"] = LinkBytes(now);
    r["testbed"] = t;
    return;
  }
  TraceStats stats;
  try {
    stats = TraceStats::FromJson(r);
  } catch (const nlohmann::json::exception&) {
    throw UserError("--testbed: method '" + method + "' does not report counted work");
  }
  if (Simulated()) {
    // seq/simd under smpirun on a platform (tools/testbed/simrun.sh --children 0): the
    // counted work is charged to this rank's simulated host, the array's cycles to the
    // platform's array host and the matrix to the link between them, as for hetero.
    const double start = SimulatedNow();
    t["testbed"] = testbedName;
    t["clock"] = "SimGrid (simulated seconds of the charged work on the platform's hosts)";
    t["hostProfile"] = SimulatedHost();
    if (method == "simd") {
      const nlohmann::json& pass = r.at("simd");
      const double arrayStart = SimulatedNow();
      ChargeArrayCycles(pass.at("cycles"), RefineCycles(pass),
                        pass.at("uncertain").at("recomputed").get<uint64_t>(), scene,
                        "SIMD/sequential");
      t["array"] = {{"seconds", SimulatedNow() - arrayStart},
                    {"what", "array cycles at the array host's speed, the matrix over the link to "
                             "it, the uncertain pixels recomputed on this host"}};
    }
    t["host"] = {{"seconds", ChargeHostWork(stats)}, {"events", stats.ToJson()}};
    t["modelledSeconds"] = SimulatedNow() - start;
    r["testbed"] = t;
    return;
  }
  const Testbed& bed = TestbedNamed(testbedName);
  const HostProfile& host = HostProfileNamed(bed.parentProfile);
  t["testbed"] = bed.Json();
  t["hostProfile"] = host.Json();
  if (method == "simd") {
    const nlohmann::json& pass = r.at("simd");
    if (pass.at("cycles").at("profile").get<std::string>() != bed.arrayProfile)
      throw UserError("--testbed " + bed.name + ": its array is '" + bed.arrayProfile +
                      "', but --machine chose '" + pass.at("cycles").at("profile").get<std::string>() + "'");
    // The host recomputes each uncertain pixel against every object, in double.
    stats.Add(RecomputeWork(pass.at("uncertain").at("recomputed").get<uint64_t>(), scene));
    const ArraySplit a = SplitPass(pass.at("cycles"), RefineCycles(pass));
    const HostTime h = ModelHostTime(stats, host);
    t["array"] = {{"profile", bed.arrayProfile},  {"clockHz", a.clockHz},
                  {"cycles", a.arrayCycles},      {"seconds", a.arraySeconds},
                  {"scsiBytes", a.scsiBytes},     {"scsiSeconds", a.scsiSeconds},
                  {"refineCycles", a.refineCycles},
                  {"cyclesSource", "the first pass's cycle report, and the refine pass's if one ran"},
                  {"scsiSource", "the cycle reports' host class (hostPlane cycles of the matrix)"}};
    t["host"] = h.Json();
    t["modelledSeconds"] = a.arraySeconds + a.scsiSeconds + h.seconds;
  } else {
    const HostTime h = ModelHostTime(stats, host);
    t["host"] = h.Json();
    t["modelledSeconds"] = h.seconds;
  }
  r["testbed"] = t;
}

namespace {
// XML comments may not hold "--" (a flag's name in a source note).
std::string Comment(std::string text) {
  for (size_t at; (at = text.find("--")) != std::string::npos;) text.replace(at, 2, "-");
  return text;
}
}  // namespace

nlohmann::json CalibrateThisHost(const nlohmann::json& r, const std::string& file) {
  if (r.value("method", "") != "seq")
    throw UserError(file + ": calibrate from a report of `zephyr render --method seq` (this is '" +
                    r.value("method", std::string("?")) + "')");
  TraceStats stats;
  double seconds = 0;
  try {
    stats = TraceStats::FromJson(r);
    seconds = r.at("phases").at("render").get<double>();
  } catch (const nlohmann::json::exception&) {
    throw UserError(file + ": the report has no counted work or no phases.render time");
  }
  if (!(seconds > 0)) throw UserError(file + ": phases.render is not a positive time");
  const HostTime h = ModelHostTime(stats, HostProfileNamed("sparcstation2"));  // counts only
  const double ops = h.flops + h.instructions;
  return {{"profile", "this-host"},
          {"operationsPerSecond", ops / seconds},
          {"operations", ops},
          {"flops", h.flops},
          {"instructions", h.instructions},
          {"measuredSeconds", seconds},
          {"source", "zephyr testbed calibrate --report " + file +
                         ": the work table's operations of that seq render over its measured render "
                         "seconds; flops and instructions at one rate (assumed)"},
          {"use", "zephyr testbed platform --host-ops " + std::to_string(ops / seconds) +
                      " --children K --out this-host.xml"}};
}

std::string PlatformXml(const Testbed& bed, int children, double hostOps) {
  if (children < 1 || children > kMaxPlatformChildren)
    throw UserError("--children: expected 1.." + std::to_string(kMaxPlatformChildren) + ", got " +
                    std::to_string(children));
  const HostProfile& parent = HostProfileNamed(bed.parentProfile);
  const HostProfile& child = HostProfileNamed(bed.childProfile);
  const bitserial::MachineProfile array = bitserial::Profile(bed.arrayProfile);
  auto host = [](const std::string& id, double speed, const std::string& profile,
                 const std::string& role) {
    std::string s = "    <host id=\"" + id + "\" speed=\"" + std::to_string(speed) + "f\">\n";
    if (!profile.empty()) s += "      <prop id=\"zephyr:profile\" value=\"" + profile + "\"/>\n";
    s += "      <prop id=\"zephyr:role\" value=\"" + role + "\"/>\n    </host>\n";
    return s;
  };
  std::string x =
      "<?xml version='1.0'?>\n"
      "<!DOCTYPE platform SYSTEM \"https://simgrid.org/simgrid.dtd\">\n"
      "<!-- Written by zephyr testbed platform (testbed " + bed.name + ", " +
      std::to_string(children) + " children; docs/testbed.md): " + Comment(bed.description) + ".\n"
      + (hostOps > 0
             ? "     Parent and children: this host calibrated (zephyr testbed calibrate), one counted "
               "operation per flop of speed; the array's speed is its clock (cycles/s). -->\n"
             : "     Host speeds are the profiles' Linpack rates (flops/s) and the array's clock "
               "(cycles/s);\n     work is charged as the profiles' modelled seconds, so the speeds "
               "only convert. -->\n") +
      "<platform version=\"4.1\">\n  <zone id=\"" + bed.name + "\" routing=\"Full\">\n";
  const bool calibrated = hostOps > 0;
  x += host("parent", calibrated ? hostOps : parent.mflops.value * 1e6, calibrated ? "" : parent.name, "parent");
  x += host("zephyr", array.clockHz, "", "array");
  for (int i = 1; i <= children; ++i)
    x += host("child-" + std::to_string(i), calibrated ? hostOps : child.mflops.value * 1e6,
              calibrated ? "" : child.name, "child");
  x += "    <!-- " + Comment(bed.ethernetBandwidth.source + "; " + bed.ethernetLatency.source) + " -->\n";
  x += "    <link id=\"ethernet\" bandwidth=\"" + std::to_string(bed.ethernetBandwidth.value) +
       "bps\" latency=\"" + std::to_string(bed.ethernetLatency.value) +
       "s\" sharing_policy=\"SHARED\"/>\n";
  x += "    <!-- " + Comment(bed.scsiBandwidth.source) + " -->\n";
  x += "    <link id=\"scsi\" bandwidth=\"" + std::to_string(bed.scsiBandwidth.value) +
       "Bps\" latency=\"0s\"/>\n";
  x += "    <route src=\"parent\" dst=\"zephyr\"><link_ctn id=\"scsi\"/></route>\n";
  for (int i = 1; i <= children; ++i)
    x += "    <route src=\"parent\" dst=\"child-" + std::to_string(i) +
         "\"><link_ctn id=\"ethernet\"/></route>\n";
  x += "  </zone>\n</platform>\n";
  return x;
}

std::string Hostfile(int children) {
  std::string s = "parent\n";
  for (int i = 1; i <= children; ++i) s += "child-" + std::to_string(i) + "\n";
  return s;
}


// ---- Simulation ---------------------------------------------------------------------------
#ifdef ZEPHYR_SMPI

bool Simulated() { return true; }

double SimulatedNow() { return simgrid::s4u::Engine::get_clock(); }

namespace {
const HostProfile* ProfileOf(simgrid::s4u::Host* h) {
  const char* name = h->get_property("zephyr:profile");
  return name ? &HostProfileNamed(name) : nullptr;
}
}  // namespace

nlohmann::json SimulatedHost() {
  simgrid::s4u::Host* h = simgrid::s4u::this_actor::get_host();
  const HostProfile* p = ProfileOf(h);
  return {{"host", h->get_name()}, {"speedFlops", h->get_speed()},
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

namespace {
nlohmann::json LinkBytes(double now) {
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
}  // namespace

double ChargeArrayPass(const simd::PrimaryPass& pass, const Scene& scene) {
  return ChargeArrayCycles(pass.cycles,
                           pass.refine.is_null() ? nlohmann::json() : pass.refine.at("cycles"),
                           uint64_t(pass.recomputedPixels), scene, "heterogeneous");
}

double ChargeArrayCycles(const nlohmann::json& cycles, const nlohmann::json& refineCycles,
                         uint64_t recomputedPixels, const Scene& scene, const std::string& method) {
  const double start = SimulatedNow();
  simgrid::s4u::Host* self = simgrid::s4u::this_actor::get_host();
  const auto arrays = simgrid::s4u::Engine::get_instance()->get_filtered_hosts([](simgrid::s4u::Host* h) {
    const char* role = h->get_property("zephyr:role");
    return role && std::string(role) == "array";
  });
  if (arrays.size() != 1)
    throw UserError("the platform has " + std::to_string(arrays.size()) +
                    " hosts with zephyr:role=array; the " + method + " method needs exactly one "
                    "(docs/testbed.md)");
  const ArraySplit a = SplitPass(cycles, refineCycles);
  // The array computes at its clock (the platform gives its speed in cycles per second).
  simgrid::s4u::this_actor::exec_init(a.arrayCycles)->set_host(arrays[0])->wait();
  if (a.scsiBytes > 0) simgrid::s4u::Comm::sendto(arrays[0], self, uint64_t(a.scsiBytes));
  passHost += ChargeHostWork(RecomputeWork(recomputedPixels, scene));
  return SimulatedNow() - start;
}

#else

bool Simulated() { return false; }
double SimulatedNow() { return 0; }
nlohmann::json SimulatedHost() { return nlohmann::json::object(); }
double ChargeHostWork(const TraceStats&) { return 0; }
double ChargeArrayPass(const simd::PrimaryPass&, const Scene&) { return 0; }
double ChargeArrayCycles(const nlohmann::json&, const nlohmann::json&, uint64_t, const Scene&,
                         const std::string&) {
  return 0;
}
void StartLinkAccounting() {}
namespace {
nlohmann::json LinkBytes(double) { return nlohmann::json::array(); }
}  // namespace

#endif

}  // namespace zephyr::testbed
