// hosts/cmd/testbed.cpp — `zephyr testbed profiles|platform|calibrate`: the modelled 1992
// testbed's host profiles and work table with their sources, its SimGrid platform file and
// hostfile, and this host's speed calibrated from a measured render (hosts/testbed/testbed.h;
// docs/testbed.md).
#include "hosts/testbed/testbed.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "bitserial/profile.h"
#include "fixed/check.h"
#include "fixed/input_file.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/io/output_file.h"
#include "hosts/testbed/host_profile.h"

namespace zephyr::testbed {
namespace {

CommandRegistration testbedCommand("testbed", [](CLI::App& program) {
  auto* cmd =
      program.add_subcommand("testbed",
                             "Testbeds (the paper's 1992 one, present-day ones): host profiles, "
                             "platform files");
  cmd->require_subcommand(1);
  auto* profiles =
      cmd->add_subcommand("profiles", "Print the host profiles and the work table, with sources");
  profiles->callback([] {
    for (const auto& name : HostProfileNames())
      std::printf("%s\n", HostProfileNamed(name).Table().c_str());
    std::printf("work table (per counted event):\n");
    for (int e = 0; e < kWorkEvents; ++e)
      std::printf("  %-12s %5g flops %5g instructions  %s\n", WorkEventName(WorkEvent(e)),
                  CostOf(WorkEvent(e)).flops, CostOf(WorkEvent(e)).instructions,
                  CostOf(WorkEvent(e)).source.c_str());
    for (const auto& name : TestbedNames())
      std::printf("\ntestbed %s:\n%s\n", name.c_str(), TestbedNamed(name).Json().dump(2).c_str());
  });
  auto* show =
      cmd->add_subcommand("show", "Print one testbed as JSON, every entry with its source");
  auto shown = std::make_shared<std::string>("ufmg1992");
  show->add_option("testbed", *shown, "Testbed name")->capture_default_str();
  show->callback([shown] {
    const Testbed& t = TestbedNamed(*shown);
    nlohmann::json j = t.Json();  // with its hosts' rates and the array's clock (what-if runs)
    j["parentHost"] = HostProfileNamed(t.parentProfile).Json();
    j["childHost"] = HostProfileNamed(t.childProfile).Json();
    j["arrayClockHz"] = bitserial::Profile(t.arrayProfile).clockHz;
    std::printf("%s\n", j.dump(2).c_str());
  });
  auto* platform =
      cmd->add_subcommand("platform", "Write a SimGrid platform file (and hostfile) of a testbed");
  auto bed = std::make_shared<std::string>("ufmg1992");
  auto children = std::make_shared<int>(8);
  auto out = std::make_shared<std::string>();
  auto hostfile = std::make_shared<std::string>();
  platform->add_option("--testbed", *bed, "Testbed name")->capture_default_str();
  AddInteger(*platform, "--children", *children, 1, kMaxPlatformChildren, "Number of child hosts");
  platform->add_option("--out", *out, "Platform XML (default: standard output)");
  platform->add_option("--hostfile", *hostfile,
                       "Also write smpirun's hostfile: the parent, then the children");
  auto bps = std::make_shared<double>(0);
  AddNumber(*platform, "--ethernet-bps", *bps, 1e3, kNoUpperEnd,
            "Override the Ethernet's bandwidth, bit/s (what-if runs)");
  auto latency = std::make_shared<double>(-1);
  AddNumber(*platform, "--ethernet-latency", *latency, 0, 10,
            "Override the Ethernet's one-way message latency, s (what-if runs)");
  auto poll = std::make_shared<double>(0);
  AddNumber(*platform, "--mpi-poll", *poll, 1e-9, 1,
            "Override the simulated seconds of each MPI_Test and MPI_Iprobe (what-if runs)");
  auto arrayClock = std::make_shared<double>(0);
  AddNumber(*platform, "--array-clock", *arrayClock, 1e3, kNoUpperEnd,
            "Override the array host's clock, Hz: its cycles take cycles/Hz (what-if runs)");
  auto hostOps = std::make_shared<double>(0);
  AddNumber(*platform, "--host-ops", *hostOps, 1e3, kNoUpperEnd,
            "Parent and children run this many counted operations per second, no profile "
            "(the this-host speed from `zephyr testbed calibrate`)");
  platform->callback([bed, children, out, hostfile, bps, latency, poll, arrayClock, hostOps] {
    Testbed t = TestbedNamed(*bed);
    if (*bps < 0 || (*bps > 0 && *bps < 1e3))
      throw UserError("--ethernet-bps: expected a bandwidth of at least 1000 bit/s");
    if (*bps > 0)
      t.ethernetBandwidth = {*bps, "bit/s", "--ethernet-bps (what-if; not the testbed's network)"};
    if (*poll > 0) t.mpiPollSeconds = {*poll, "s", "--mpi-poll (what-if; not the testbed's)"};
    if (*latency >= 0)
      t.ethernetLatency = {*latency, "s",
                           "--ethernet-latency (what-if; not the testbed's network)"};
    if (*hostOps < 0 || (*hostOps > 0 && *hostOps < 1e3))
      throw UserError("--host-ops: expected at least 1000 operations per second");
    CheckOutputs({{"--out", *out}, {"--hostfile", *hostfile}});
    const std::string xml = PlatformXml(t, *children, *hostOps, *arrayClock);
    if (out->empty())
      std::fputs(xml.c_str(), stdout);
    else
      WriteOutputFile(*out, "platform file", xml);
    if (!hostfile->empty()) WriteOutputFile(*hostfile, "hostfile", Hostfile(*children));
  });
  auto* calibrate = cmd->add_subcommand(
      "calibrate",
      "This host's speed (the this-host profile) from a measured `render --method seq --report`");
  auto report = std::make_shared<std::string>();
  calibrate->add_option("--report", *report, "JSON report of a seq render measured on this host")
      ->required();
  calibrate->callback([report] {
    const std::string text =
        ReadInputFile(*report, {"the report", "a JSON render report"}, std::uintmax_t(64) << 20);
    RefuseNulBytes(text, *report);  // nlohmann would stop reading at it
    nlohmann::json r;
    try {
      r = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
      throw UserError(*report + ": not a JSON report: " + e.what());
    }
    std::printf("%s\n", CalibrateThisHost(r, *report).dump(2).c_str());
  });
});

}  // namespace
}  // namespace zephyr::testbed
