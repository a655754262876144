// The `zephyr` program: subcommands are registered by the modules that own them
// (see hosts/cmd/command.h).
#include "hosts/cmd/command.h"

int main(int argc, char** argv) { return zephyr::RunZephyr(argc, argv); }
