#include "hosts/cmd/command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <map>

#include "fixed/check.h"

namespace zephyr {

namespace {
std::map<std::string, CommandSetup>& Registry() {
  static std::map<std::string, CommandSetup> registry;  // sorted by name
  return registry;
}
}  // namespace

CommandRegistration::CommandRegistration(std::string name, CommandSetup setup) {
  Registry().emplace(std::move(name), std::move(setup));
}

void AddRegisteredCommands(CLI::App& program) {
  for (auto& [name, setup] : Registry()) setup(program);
}

int RunZephyr(int argc, const char* const* argv) {
  CLI::App program{
      "zephyr — an emulated WaveTracer Zephyr (8192 bit-serial PEs) and the paper's four "
      "ray-tracing methods"};
  program.require_subcommand(1);
  AddRegisteredCommands(program);
  try {
    program.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // (program.exit): parenthesised so SMPI's exit(x) macro (zephyr-smpi, docs/testbed.md)
    // leaves CLI11's member alone.
    return (program.exit)(e);
  } catch (const UserError& e) {
    std::fprintf(stderr, "zephyr: error: %s\n", e.what());
    return e.ExitCode();
  }
  return 0;
}

}  // namespace zephyr
