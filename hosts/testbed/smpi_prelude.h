// hosts/testbed/smpi_prelude.h — force-included after SimGrid's smpi_helpers.h when the
// sources are built for SMPI (`make smpi`, docs/testbed.md); never in the ordinary build.
//
// smpi_helpers.h defines exit(x) as a macro so that a simulated rank that calls exit ends
// only itself; CLI11 declares a member function named exit with three arguments, which the
// one-argument macro cannot parse. CLI11 is read here with the macro lifted, then the macro
// is restored for every other source (a child's std::exit must still end only that rank).
#pragma once
#undef exit
#include <CLI/CLI.hpp>
#define exit(x) smpi_exit(x)
