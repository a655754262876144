// The `zephyr` program: subcommands are registered by the modules that own them
// (see hosts/cmd/command.h).
#include "hosts/cmd/command.h"

#ifdef ZEPHYR_SMPI
#include <mpi.h>

#include "hosts/farm/session.h"

// zephyr-smpi (docs/testbed.md): finalize before main returns, as SMPI requires.
int main(int argc, char** argv) {
  const int status = zephyr::RunZephyr(argc, argv);
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized) zephyr::FinalizeMpiAtExit();
  return status;
}
#else
int main(int argc, char** argv) { return zephyr::RunZephyr(argc, argv); }
#endif
