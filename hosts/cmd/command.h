// hosts/cmd/command.h — the `zephyr` program's subcommands register themselves here.
//
// Each command is one file of hosts/cmd/ (render.cpp, plan.cpp, cycles.cpp, ...) that holds
// its flags and adds itself with a file-scope CommandRegistration, so no central list has to
// be edited when a command is added; the code it drives lives in the rooms below.
#pragma once

#include <functional>
#include <string>

namespace CLI {
class App;
}

namespace zephyr {

// Adds one subcommand (with its options and callback) to the program's CLI11 app.
using CommandSetup = std::function<void(CLI::App& program)>;

struct CommandRegistration {
  CommandRegistration(std::string name, CommandSetup setup);
};

// Calls every registered setup, in name order (used by hosts/cmd/main.cpp and the tests).
void AddRegisteredCommands(CLI::App& program);

// Every option of `app` and its subcommands that takes a value (not a flag) refuses an empty one
// (`--testbed ''`, `--out ''`, a positional ''): a mistake, never "the default" (CLI11's
// validation error: "--testbed: empty value (give one, or leave the flag out)", exit non-zero
// before any work). RunZephyr applies it to the whole program.
void RefuseEmptyValues(CLI::App& app);

// Runs the program as `zephyr args...` would, returning the exit status; the tests use it
// to check messages and exit codes without a subprocess.
int RunZephyr(int argc, const char* const* argv);

}  // namespace zephyr
