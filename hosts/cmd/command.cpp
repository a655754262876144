#include "hosts/cmd/command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <map>

#include "fixed/check.h"
#include "hosts/cmd/flags.h"

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

void RefuseEmptyValues(CLI::App& app) {
  const CLI::Validator nonEmpty(
      [](std::string& value) {
        return value.empty() ? std::string("empty value (give one, or leave the flag out)")
                             : std::string();
      },
      "", "non-empty");
  for (CLI::Option* option :
       app.get_options([](CLI::Option* o) { return o->get_expected_min() > 0; }))
    option->check(nonEmpty);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) RefuseEmptyValues(*sub);
}

// How long a silent rank waits after a command-line mistake before it exits (rank 0 prints
// and exits in microseconds; mpirun then ends the waiting ranks).
constexpr std::chrono::seconds kSilentRankWait{5};

int RunZephyr(int argc, const char* const* argv) {
  CLI::App program{
      "zephyr — an emulated WaveTracer Zephyr (8192 bit-serial PEs) and the paper's four "
      "ray-tracing methods"};
  program.require_subcommand(1);
  AddRegisteredCommands(program);
  RefuseEmptyValues(program);
  // A command line's mistake is the same on every rank of an mpirun: rank 0 alone says it
  // (the others exit with the same status, silently).
  const bool speak = LauncherRank() == 0;
  program.failure_message([speak](const CLI::App* app, const CLI::Error& e) -> std::string {
    if (!speak) return "";
    std::string where = "zephyr";  // the subcommands as far as they were read: "zephyr gen spheres"
    for (const CLI::App* a = app; a && !a->get_subcommands().empty();) {
      a = a->get_subcommands().front();
      where += " " + a->get_name();
    }
    return "zephyr: error: " + std::string(e.what()) + "\n(run '" + where +
           " --help' for the flags)\n";
  });
  try {
    program.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // (program.exit): parenthesised so SMPI's exit(x) macro (zephyr-smpi, docs/testbed.md)
    // leaves CLI11's member alone.
    const int status = (program.exit)(e);
    // A silent rank lets rank 0 say it first: mpirun ends the job at the first rank that exits
    // non-zero, and on a loaded machine a silent rank's exit ended rank 0 before it had written
    // the message (the user saw none). Rank 0's own exit then ends this wait at once.
    if (!speak && status != 0) std::this_thread::sleep_for(kSilentRankWait);
    return status;
  } catch (const UserError& e) {
    std::fprintf(stderr, "zephyr: error: %s\n", e.what());
    return e.ExitCode();
  } catch (const std::bad_alloc&) {
    // The runs' own estimates refuse what cannot fit before any work (docs/errors.md,
    // "Memory"); this is the last line, for what no estimate foresaw.
    std::fprintf(stderr,
                 "zephyr: error: out of memory (the process could not allocate what this run "
                 "needs; try a smaller resolution, fewer threads or a larger memory limit)\n");
    return 1;
  }
  return 0;
}

}  // namespace zephyr
