#include "hosts/testbed/testbed.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "bitserial/profile.h"
#include "fixed/check.h"
#include "hosts/testbed/simulation.h"

namespace zephyr::testbed {

namespace {

// A present-day core calibrated (host_profile.cpp "today-calibrated") behind 25 GbE: the
// network of both present-day testbeds (docs/present-day.md (b)).
constexpr double kTodayEthernetBps = 25e9;
const char* const kTodayEthernetSource =
    "IEEE 802.3by-2016: 25 Gb/s Ethernet line rate (SimGrid's link gets the line rate; TCP's "
    "payload share at MTU 1500, 94 %, is not modelled)";
constexpr double kTodayLatency = 1.6e-5;
const char* const kTodayLatencySource =
    "sockperf ping-pong --tcp, 400-byte messages, between two cloud VMs (Mellanox/sockperf "
    "issue #155, 2021): 31.2 us a round trip, 15.6 us one way; the NIC's speed not stated "
    "(assumed 25 Gb/s class); MPI's own cost on top assumed 0 (docs/present-day.md (b))";
constexpr double kTodayPoll = 1e-6;
const char* const kTodayPollSource =
    "assumed: a present-day MPI_Test or MPI_Iprobe is a call into the progress engine of the "
    "order of a microsecond (no published figure found; SimGrid's default 1e-4 s is a 1990s "
    "daemon round trip and would poll away the parent's time)";
const char* const kSwitchedSource =
    "assumed: a present-day cluster's hosts each on their own full-duplex port of one "
    "switch whose backplane never limits; a port is modelled as one SHARED link (both "
    "directions share it: the farm's traffic is mostly one way at a time)";

const std::map<std::string, Testbed>& Testbeds() {
  static const std::map<std::string, Testbed> testbeds = {
      {"ufmg1992",
       {"ufmg1992",
        "the paper's runs (§6.1): a SPARCstation 2 host/parent with the Zephyr on SCSI, "
        "SPARCstation SLC children, the department's Ethernet under PVM",
        "sparcstation2",
        "sparcstation-slc",
        "wavetracer",
        {10e6, "bit/s",
         "assumed: the SPARCstations' built-in 10 Mbit/s Ethernet (10BASE), one "
         "medium shared by every station"},
        {1e-3, "s",
         "assumed: per-message latency of PVM 3 over Ethernet of the order of a "
         "millisecond (daemon-routed UDP)"},
        EthernetTopology::kShared,
        "assumed: 10BASE coax or a hub, one collision domain: every station's traffic "
        "shares one medium",
        "scsi",
        {5e6, "byte/s",
         "assumed: SCSI-1 synchronous at 5 MB/s, the same figure as the "
         "wavetracer profile's hostPlane cost"},
        {1e-4, "s",
         "SimGrid 3.32's default for smpi/test and smpi/iprobe (not from a source), kept as "
         "the 1992 model ran: PVM 3's polling (pvm_nrecv) was of that order, a daemon round "
         "trip"}}},
      {"today-zephyr",
       {"today-zephyr",
        "the paper's future work (§8) on a present-day cluster: the Zephyr as it would "
        "stand today (10 MHz, SCSI-1) behind a present-day host and children on switched "
        "25 GbE (docs/present-day.md)",
        "today-calibrated",
        "today-calibrated",
        "wavetracer",
        {kTodayEthernetBps, "bit/s", kTodayEthernetSource},
        {kTodayLatency, "s", kTodayLatencySource},
        EthernetTopology::kSwitched,
        kSwitchedSource,
        "scsi",
        {5e6, "byte/s",
         "the Zephyr's own board: SCSI-1 synchronous at 5 MB/s (assumed, as ufmg1992), the "
         "wavetracer profile's hostPlane cost"},
        {kTodayPoll, "s", kTodayPollSource}}},
      {"today-pim",
       {"today-pim",
        "the paper's future work (§8) on present-day parts: a bit-serial processing-in-DRAM "
        "array (PIMeval's BitSIMD-V, one DDR4-3200 bank, 262,144 PEs at 1.6 GHz) on the "
        "host's memory bus, present-day host and children on switched 25 GbE "
        "(docs/present-day.md)",
        "today-calibrated",
        "today-calibrated",
        "pim-bitsimd-v-bank",
        {kTodayEthernetBps, "bit/s", kTodayEthernetSource},
        {kTodayLatency, "s", kTodayLatencySource},
        EthernetTopology::kSwitched,
        kSwitchedSource,
        "memory-bus",
        {25.6e9, "byte/s",
         "JEDEC JESD79-4 DDR4-3200: 3200 MT/s x 64 bits = 25.6 GB/s, one channel (PIMeval's "
         "host<->PIM copies use the same figure, pimParamsDDRDram.h m_typicalRankBW); the "
         "pim-bitsimd-v-bank profile's hostPlane cost (docs/present-day.md (c))"},
        {kTodayPoll, "s", kTodayPollSource}}},
  };
  return testbeds;
}

}  // namespace

ArraySplit SplitArrayCycles(const bitserial::CycleReport& first,
                            const bitserial::CycleReport* refine) {
  ArraySplit a;
  const bitserial::MachineProfile& profile = first.Profile();
  a.clockHz = profile.clockHz;
  double host = 0;
  for (const bitserial::CycleReport* pass : {&first, refine}) {
    if (!pass) continue;
    ZEPHYR_CHECK(pass->Profile().clockHz == a.clockHz);
    const double passHost = pass->ClassCycles(bitserial::CycleClass::kHost);
    a.arrayCycles += pass->TotalCycles() - passHost;
    host += passHost;
    if (pass == refine) a.refineCycles = pass->TotalCycles();
  }
  a.arraySeconds = a.arrayCycles / a.clockHz;
  a.linkSeconds = host / a.clockHz;
  const double planeCycles = profile.Cost(bitserial::MicroOp::kHostPlane);
  a.linkBytes = planeCycles > 0 ? host / planeCycles * profile.physicalPes / 8 : 0;
  return a;
}

nlohmann::json Testbed::Json() const {
  return {{"name", name},
          {"description", description},
          {"parentProfile", parentProfile},
          {"childProfile", childProfile},
          {"arrayProfile", arrayProfile},
          {"ethernetBandwidth", ethernetBandwidth.Json()},
          {"ethernetLatency", ethernetLatency.Json()},
          {"ethernetTopology",
           {{"value", ethernetTopology == EthernetTopology::kShared ? "shared" : "switched"},
            {"source", ethernetTopologySource}}},
          {"arrayLink", arrayLink},
          {"arrayLinkBandwidth", arrayLinkBandwidth.Json()},
          {"mpiPollSeconds", mpiPollSeconds.Json()}};
}

const Testbed& TestbedNamed(const std::string& name) {
  auto it = Testbeds().find(name);
  if (it == Testbeds().end()) {
    std::string known;
    for (const auto& n : TestbedNames()) known += (known.empty() ? "" : ", ") + n;
    if (std::filesystem::is_regular_file(name))
      throw UserError("testbed '" + name +
                      "': a platform file is simulated — run the render under "
                      "`tools/testbed/simrun.sh --children K --platform " +
                      name + " -- render ...` (K = 0 for seq and simd; docs/testbed.md)");
    throw UserError("unknown testbed '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

std::optional<std::string> TestbedArrayProfile(const std::string& name) {
  auto it = Testbeds().find(name);
  if (it == Testbeds().end()) return std::nullopt;
  return it->second.arrayProfile;
}

std::vector<std::string> TestbedNames() {
  std::vector<std::string> names;
  for (const auto& [name, t] : Testbeds()) names.push_back(name);
  return names;
}

namespace {

// One testbed of a request: its name known, its array the pass's, a farmed method simulated.
void CheckModelledTimeRequest(const std::string& testbedName, const std::string& method,
                              bool farmed, bool usesArray, const std::string& arrayProfile) {
  if (testbedName.empty()) return;
  if (!Simulated()) {
    const Testbed& bed = TestbedNamed(testbedName);  // an unknown name first
    if (farmed)
      throw UserError("a testbed's time of method '" + method +
                      "' runs on a simulated network: build/bin/zephyr-smpi under smpirun "
                      "(tools/testbed/simrun.sh --testbed " +
                      testbedName + "; `make smpi`; docs/testbed.md)");
    if (usesArray && arrayProfile != bed.arrayProfile)
      throw UserError("testbed '" + bed.name + "': its array is '" + bed.arrayProfile +
                      "', but the machine profile is '" + arrayProfile + "'");
    return;
  }
  // The platform file names the hosts; a testbed's own platform must be the testbed named,
  // and its array the machine profile the pass runs.
  const std::string platform = SimulatedPlatformName();
  if (Testbeds().count(testbedName) && Testbeds().count(platform) && platform != testbedName)
    throw UserError("testbed '" + testbedName + "': the simulated platform is testbed '" +
                    platform + "''s (tools/testbed/simrun.sh --testbed " + testbedName + ")");
  const std::string array = SimulatedArrayProfile();
  if (usesArray && !array.empty() && array != arrayProfile)
    throw UserError("the simulated platform's array is '" + array +
                    "', but the machine profile is '" + arrayProfile + "'");
}

}  // namespace

void CheckPricingRequest(const PricingRequest& r) {
  if (!r.alsoTestbeds.empty()) {
    if (r.testbed.empty())
      throw UserError("more testbeds to price a render on need a first one (the testbed)");
    if (r.farmed || Simulated())
      throw UserError("method '" + r.method +
                      "' is timed by a simulation of one testbed's network: one testbed a run");
    std::vector<std::string> seen = {r.testbed};
    const auto first = TestbedArrayProfile(r.testbed);
    for (const std::string& bed : r.alsoTestbeds) {
      if (std::find(seen.begin(), seen.end(), bed) != seen.end())
        throw UserError("testbed '" + bed + "' is named twice: each is priced once");
      seen.push_back(bed);
      const auto also = TestbedArrayProfile(bed);
      if (r.usesArray && first && also && *first != *also)
        throw UserError("testbed '" + bed + "' has the array '" + *also + "' and testbed '" +
                        r.testbed + "' the array '" + *first +
                        "': a render runs one array, so the testbeds it is priced on must share it");
      CheckModelledTimeRequest(bed, r.method, false, r.usesArray, r.arrayProfile);
    }
  }
  CheckModelledTimeRequest(r.testbed, r.method, r.farmed, r.usesArray, r.arrayProfile);
}

namespace {

// A farmed render under simulation: SimGrid's clock, the parent's split, the children's.
ModelledTime FarmTime(const std::string& testbedName, const FarmTimes& farm) {
  if (!Simulated())
    throw UserError(
        "a testbed's time of a farmed method runs on a simulated network: build/bin/zephyr-smpi "
        "under smpirun (`make smpi`; docs/testbed.md)");
  ModelledTime t;
  t.testbed = testbedName;
  const double now = SimulatedNow();
  t.modelledSeconds = now;
  t.clock = "SimGrid (simulated seconds from MPI start to the finished image at the parent)";
  t.simulatedHost = SimulatedHost();
  ModelledTime::FarmSplit f;
  f.arrayPassSeconds = farm.parentPassSeconds;
  f.hostWorkSeconds = ChargedHostSeconds() - ChargedPassHostSeconds();
  f.waitingSeconds = now - f.hostWorkSeconds - farm.parentPassSeconds;
  for (const FarmTimes::Child& c : farm.children) {
    ModelledTime::FarmSplit::Child child{.rank = c.rank, .host = c.host};
    if (c.busySeconds) child.busySeconds = *c.busySeconds, child.idleSeconds = now - *c.busySeconds;
    f.children.push_back(child);
  }
  f.links = LinkLoads(now);
  t.farm = std::move(f);
  return t;
}

}  // namespace

std::optional<ModelledTime> ModelTime(const std::string& testbedName, const CountedWork& work,
                                      const Scene& scene) {
  if (testbedName.empty()) return std::nullopt;
  if (work.farm) return FarmTime(testbedName, *work.farm);
  if (!work.host)
    throw UserError("testbed '" + testbedName + "': the method counts no host work to model");
  TraceStats stats = *work.host;
  ModelledTime t;
  t.testbed = testbedName;
  if (Simulated()) {
    // seq/simd under smpirun on a platform (tools/testbed/simrun.sh --children 0): the
    // counted work is charged to this rank's simulated host, the array's cycles to the
    // platform's array host and the matrix to the link between them, as for hetero.
    const double start = SimulatedNow();
    t.clock = "SimGrid (simulated seconds of the charged work on the platform's hosts)";
    t.simulatedHost = SimulatedHost();
    if (work.arrayCycles) {
      const double arrayStart = SimulatedNow();
      ChargeArrayCycles(*work.arrayCycles, work.refineCycles,
                        work.recomputeWork ? RecomputeWork(*work.recomputeWork)
                                           : RecomputeWork(work.recomputedPixels, scene),
                        "SIMD/sequential");
      t.simulatedArraySeconds = SimulatedNow() - arrayStart;
    }
    t.simulatedHostSeconds = ChargeHostWork(stats);
    t.simulatedEvents = stats;
    t.modelledSeconds = SimulatedNow() - start;
    return t;
  }
  const Testbed& bed = TestbedNamed(testbedName);
  const HostProfile& host = HostProfileNamed(bed.parentProfile);
  t.bed = &bed;
  t.hostProfile = &host;
  double arraySeconds = 0;
  if (work.arrayCycles) {
    const std::string& profile = work.arrayCycles->Profile().name;
    if (profile != bed.arrayProfile)
      throw UserError("testbed '" + bed.name + "': its array is '" + bed.arrayProfile +
                      "', but the machine profile is '" + profile + "'");
    // The host recomputes each uncertain pixel against every object, in double.
    stats.Add(work.recomputeWork ? RecomputeWork(*work.recomputeWork)
                                 : RecomputeWork(work.recomputedPixels, scene));
    t.array =
        ModelledTime::ArrayShare{profile, SplitArrayCycles(*work.arrayCycles, work.refineCycles)};
    arraySeconds = t.array->split.arraySeconds + t.array->split.linkSeconds;
  }
  t.host = ModelHostTime(stats, host);
  t.modelledSeconds = arraySeconds + t.host->seconds;
  return t;
}

std::optional<double> ModelledTime::ArrayActiveShare() const {
  if (!(modelledSeconds > 0)) return std::nullopt;
  if (farm) {
    if (!(farm->arrayPassSeconds > 0)) return std::nullopt;
    return farm->arrayPassSeconds / modelledSeconds;
  }
  if (!clock.empty())
    return simulatedArraySeconds ? std::optional(*simulatedArraySeconds / modelledSeconds)
                                 : std::nullopt;
  if (!array) return std::nullopt;
  return array->split.arraySeconds / modelledSeconds;
}

nlohmann::json ModelledTime::Json() const {
  nlohmann::json t;
  if (const auto share = ArrayActiveShare()) t["arrayActiveShare"] = *share;
  if (farm) {
    t["testbed"] = testbed;
    t["modelledSeconds"] = modelledSeconds;
    t["clock"] = clock;
    t["parent"] = simulatedHost;
    t["parent"]["arrayPassSeconds"] = farm->arrayPassSeconds;
    t["parent"]["hostWorkSeconds"] = farm->hostWorkSeconds;
    t["parent"]["hostWorkSource"] =
        "pixels packed into slices and pasted from results (one work-table pixel each), "
        "degenerate frames shaded; the array pass apart";
    t["parent"]["waitingSeconds"] = farm->waitingSeconds;
    nlohmann::json children = nlohmann::json::array();
    for (const FarmSplit::Child& c : farm->children) {
      nlohmann::json j = {{"rank", c.rank}, {"host", c.host}};
      if (c.busySeconds) j["busySeconds"] = *c.busySeconds, j["idleSeconds"] = *c.idleSeconds;
      children.push_back(j);
    }
    t["children"] = children;
    t["childrenIdleSource"] = "modelledSeconds minus the child's charged work";
    t["links"] = farm->links;
    return t;
  }
  if (!clock.empty()) {  // seq/simd under simulation
    t["testbed"] = testbed;
    t["clock"] = clock;
    t["hostProfile"] = simulatedHost;
    if (simulatedArraySeconds)
      t["array"] = {{"seconds", *simulatedArraySeconds},
                    {"what",
                     "array cycles at the array host's speed, the matrix over the link to "
                     "it, the uncertain pixels recomputed on this host"}};
    t["host"] = {{"seconds", simulatedHostSeconds.value_or(0)},
                 {"events", simulatedEvents.ToJson()}};
    t["modelledSeconds"] = modelledSeconds;
    return t;
  }
  t["testbed"] = bed->Json();
  t["hostProfile"] = hostProfile->Json();
  if (array) {
    const ArraySplit& a = array->split;
    t["array"] = {{"profile", array->profile},
                  {"clockHz", a.clockHz},
                  {"cycles", a.arrayCycles},
                  {"seconds", a.arraySeconds},
                  {"linkBytes", a.linkBytes},
                  {"linkSeconds", a.linkSeconds},
                  {"refineCycles", a.refineCycles},
                  {"cyclesSource",
                   "every array run's cycle report: the first pass, the refine pass if one ran, "
                   "every wavefront bounce (all rays on the array)"},
                  {"linkSource",
                   "the cycle reports' host class (hostPlane cycles of the matrix) over the "
                   "testbed's arrayLink"}};
  }
  t["host"] = host->Json();
  t["modelledSeconds"] = modelledSeconds;
  return t;
}

namespace {
// XML comments may not hold "--" (a flag's name in a source note).
std::string Comment(std::string text) {
  for (size_t at; (at = text.find("--")) != std::string::npos;) text.replace(at, 2, "-");
  return text;
}
}  // namespace

nlohmann::json CalibrateThisHost(const nlohmann::json& r, const std::string& file) {
  if (!r.is_object())
    throw UserError(file + ": expected a render report (a JSON object), got " +
                    std::string(r.type_name()));
  const auto given = r.find("method");
  const std::string name = given == r.end()     ? "?"
                           : given->is_string() ? given->get<std::string>()
                                                : given->dump();
  if (name != "seq")
    throw UserError(file + ": calibrate from a report of `zephyr render --method seq` (this is '" +
                    name + "')");
  TraceStats stats;
  double seconds = 0;
  try {
    stats = TraceStats::FromJson(r);
    seconds = r.at("phases").at("render").get<double>();
  } catch (const nlohmann::json::exception&) {
    throw UserError(file + ": the report has no counted work or no phases.render time");
  }
  // At least a microsecond: a render of 1e-300 s would make this host infinitely fast.
  if (!(seconds >= 1e-6) || !std::isfinite(seconds))
    throw UserError(file + ": phases.render must be a time from 1e-6 s, got " +
                    nlohmann::json(seconds).dump());
  const HostTime h = ModelHostTime(stats, HostProfileNamed("sparcstation2"));  // counts only
  const double ops = h.flops + h.instructions;
  return {
      {"profile", "this-host"},
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

std::string PlatformXml(const Testbed& bed, int children, double hostOps, double arrayClockHz) {
  if (children < 1 || children > kMaxPlatformChildren)
    throw UserError("a platform's children must be 1.." + std::to_string(kMaxPlatformChildren) +
                    ", got " + std::to_string(children));
  const HostProfile& parent = HostProfileNamed(bed.parentProfile);
  const HostProfile& child = HostProfileNamed(bed.childProfile);
  const bitserial::MachineProfile array = bitserial::Profile(bed.arrayProfile);
  // A host; `arrayProfile`: the machine profile an array host declares, which a render on the
  // platform must run.
  auto host = [](const std::string& id, double speed, const std::string& profile,
                 const std::string& role, const std::string& arrayProfile = "") {
    std::string s = "    <host id=\"" + id + "\" speed=\"" + std::to_string(speed) + "f\">\n";
    if (!profile.empty()) s += "      <prop id=\"zephyr:profile\" value=\"" + profile + "\"/>\n";
    s += "      <prop id=\"zephyr:role\" value=\"" + role + "\"/>\n";
    if (!arrayProfile.empty())
      s += "      <prop id=\"zephyr:array-profile\" value=\"" + arrayProfile + "\"/>\n";
    return s + "    </host>\n";
  };
  std::string x =
      "<?xml version='1.0'?>\n"
      "<!DOCTYPE platform SYSTEM \"https://simgrid.org/simgrid.dtd\">\n"
      "<!-- Written by zephyr testbed platform (testbed " +
      bed.name + ", " + std::to_string(children) +
      " children; docs/testbed.md): " + Comment(bed.description) + ".\n" +
      (hostOps > 0
           ? "     Parent and children: this host calibrated (zephyr testbed calibrate), one "
             "counted "
             "operation per flop of speed; the array's speed is its clock (cycles/s). -->\n"
           : "     Host speeds are the profiles' Linpack rates (flops/s) and the array's clock "
             "(cycles/s);\n     work is charged as the profiles' modelled seconds, so the speeds "
             "only convert. -->\n") +
      "<platform version=\"4.1\">\n";
  if (bed.mpiPollSeconds.value > 0) {
    const std::string poll = fmt::format("{:g}", bed.mpiPollSeconds.value);
    x += "  <!-- " + Comment(bed.mpiPollSeconds.source) +
         " -->\n  <config>\n    <prop id=\"smpi/test\" value=\"" + poll +
         "\"/>\n    <prop id=\"smpi/iprobe\" value=\"" + poll + "\"/>\n  </config>\n";
  }
  x += "  <zone id=\"" + bed.name + "\" routing=\"Full\">\n";
  const bool calibrated = hostOps > 0;
  x += host("parent", calibrated ? hostOps : parent.mflops.value * 1e6,
            calibrated ? "" : parent.name, "parent");
  x += host("zephyr", arrayClockHz > 0 ? arrayClockHz : array.clockHz, "", "array",
            bed.arrayProfile);
  for (int i = 1; i <= children; ++i)
    x += host("child-" + std::to_string(i), calibrated ? hostOps : child.mflops.value * 1e6,
              calibrated ? "" : child.name, "child");
  const std::string bps = std::to_string(bed.ethernetBandwidth.value) + "bps";
  x += "    <!-- " +
       Comment(bed.ethernetBandwidth.source + "; " + bed.ethernetLatency.source + "; " +
               bed.ethernetTopologySource) +
       " -->\n";
  const bool switched = bed.ethernetTopology == EthernetTopology::kSwitched;
  // Switched: a message crosses two ports, each half the one-way latency.
  const std::string latency =
      std::to_string(switched ? bed.ethernetLatency.value / 2 : bed.ethernetLatency.value) + "s";
  x += "    <link id=\"ethernet\" bandwidth=\"" + bps + "\" latency=\"" + latency +
       "\" sharing_policy=\"SHARED\"/>\n";
  if (switched)
    for (int i = 1; i <= children; ++i)
      x += "    <link id=\"ethernet-child-" + std::to_string(i) + "\" bandwidth=\"" + bps +
           "\" latency=\"" + latency + "\" sharing_policy=\"SHARED\"/>\n";
  x += "    <!-- " + Comment(bed.arrayLinkBandwidth.source) + " -->\n";
  x += "    <link id=\"" + bed.arrayLink + "\" bandwidth=\"" +
       std::to_string(bed.arrayLinkBandwidth.value) + "Bps\" latency=\"0s\"/>\n";
  x +=
      "    <route src=\"parent\" dst=\"zephyr\"><link_ctn id=\"" + bed.arrayLink + "\"/></route>\n";
  for (int i = 1; i <= children; ++i) {
    const std::string child = "child-" + std::to_string(i);
    x += "    <route src=\"parent\" dst=\"" + child + "\"><link_ctn id=\"ethernet\"/>" +
         (switched ? "<link_ctn id=\"ethernet-" + child + "\"/>" : "") + "</route>\n";
  }
  x += "  </zone>\n</platform>\n";
  return x;
}

std::string Hostfile(int children) {
  std::string s = "parent\n";
  for (int i = 1; i <= children; ++i) s += "child-" + std::to_string(i) + "\n";
  return s;
}

}  // namespace zephyr::testbed
