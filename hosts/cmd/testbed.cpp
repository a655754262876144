// hosts/cmd/testbed.cpp — `zephyr testbed profiles|platform`: the modelled 1992 testbed's host
// profiles and work table with their sources, and its SimGrid platform file and hostfile
// (hosts/testbed/testbed.h; docs/testbed.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/io/output_file.h"
#include "hosts/testbed/host_profile.h"
#include "hosts/testbed/testbed.h"

namespace zephyr::testbed {
namespace {

CommandRegistration testbedCommand("testbed", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("testbed", "The paper's 1992 testbed: host profiles, platform files");
  cmd->require_subcommand(1);
  auto* profiles = cmd->add_subcommand("profiles", "Print the host profiles and the work table, with sources");
  profiles->callback([] {
    for (const auto& name : HostProfileNames()) std::printf("%s\n", HostProfileNamed(name).Table().c_str());
    std::printf("work table (per counted event):\n");
    for (int e = 0; e < kWorkEvents; ++e)
      std::printf("  %-12s %5g flops %5g instructions  %s\n", WorkEventName(WorkEvent(e)),
                  CostOf(WorkEvent(e)).flops, CostOf(WorkEvent(e)).instructions,
                  CostOf(WorkEvent(e)).source.c_str());
    for (const auto& name : TestbedNames())
      std::printf("\ntestbed %s:\n%s\n", name.c_str(), TestbedNamed(name).Json().dump(2).c_str());
  });
  auto* platform = cmd->add_subcommand("platform", "Write a SimGrid platform file (and hostfile) of a testbed");
  auto bed = std::make_shared<std::string>("ufmg1992");
  auto children = std::make_shared<int>(8);
  auto out = std::make_shared<std::string>();
  auto hostfile = std::make_shared<std::string>();
  platform->add_option("--testbed", *bed, "Testbed name")->capture_default_str();
  platform->add_option("--children", *children, "Number of child hosts")->capture_default_str();
  platform->add_option("--out", *out, "Platform XML (default: standard output)");
  platform->add_option("--hostfile", *hostfile, "Also write smpirun's hostfile: the parent, then the children");
  auto bps = std::make_shared<double>(0);
  platform->add_option("--ethernet-bps", *bps, "Override the Ethernet's bandwidth, bit/s (what-if runs)");
  platform->callback([bed, children, out, hostfile, bps] {
    Testbed t = TestbedNamed(*bed);
    if (*bps < 0 || (*bps > 0 && *bps < 1e3))
      throw UserError("--ethernet-bps: expected a bandwidth of at least 1000 bit/s");
    if (*bps > 0) t.ethernetBandwidth = {*bps, "bit/s", "--ethernet-bps (what-if; not the paper's network)"};
    const std::string xml = PlatformXml(t, *children);
    if (out->empty()) std::fputs(xml.c_str(), stdout);
    else WriteOutputFile(*out, "platform file", xml);
    if (!hostfile->empty()) WriteOutputFile(*hostfile, "hostfile", Hostfile(*children));
  });
});

}  // namespace
}  // namespace zephyr::testbed
