// hosts/cmd/profile.cpp — `zephyr profile list|show`: the built-in machine profiles, and any
// profile as a file to start a new machine from (bitserial/profile.h; docs/bitserial.md,
// "Machine profiles").
//
//   zephyr profile list                              # name and machine of each built-in
//   zephyr profile show mpp > my.json                # edit, then --machine my.json
//   zephyr profile show my.json --set clockHz=20e6   # a file with overrides applied
#include "bitserial/profile.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hosts/cmd/command.h"
#include "hosts/io/output_file.h"

namespace zephyr::bitserial {
namespace {

CommandRegistration profileCommand("profile", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "profile", "Machine profiles: list the built-in ones, print one as a file to edit");
  cmd->require_subcommand(1);
  auto* list = cmd->add_subcommand("list", "The built-in machine profiles and their machines");
  list->callback([] {
    for (const std::string& name : ProfileNames())
      std::printf("%-12s %s\n", name.c_str(), Profile(name).description.c_str());
  });
  auto* show = cmd->add_subcommand(
      "show", "Print a machine profile (a built-in name or a file) as a profile file");
  auto name = std::make_shared<std::string>();
  auto overrides = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  show->add_option("machine", *name, "A built-in profile (zephyr profile list) or a file")
      ->required();
  show->add_option("--set", *overrides,
                   "Override an entry first, NAME=VALUE (as render --set; docs/bitserial.md)");
  show->add_option("--out", *out, "Write the file here (default: standard output)");
  show->callback([name, overrides, out] {
    if (!out->empty()) CheckOutputPath("--out", *out);
    MachineProfile p = Profile(*name);
    for (const std::string& s : *overrides) p.Override(s);
    const std::string text = p.FileText();
    if (out->empty())
      std::fputs(text.c_str(), stdout);
    else
      WriteOutputFile(*out, "machine profile", text);
  });
});

}  // namespace
}  // namespace zephyr::bitserial
