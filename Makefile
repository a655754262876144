# Zephyr — a cycle-faithful WaveTracer Zephyr emulator and the paper's four ray tracers.
# Plain make: objects under build/, -MMD -MP dependencies, quiet unless V=1, rebuild when
# the flags change, Debian packages installed on demand by tools/setup.sh.
#
#   make run  [SCENE=file.nff] [METHOD=...] [WORKERS=K] [FRAME=F]
#   make test [FILTER=gtest-filter]

.DEFAULT_GOAL := all
SHELL := /bin/bash

V ?= 0
ifeq ($(V),0)
  Q := @
  say = @printf '  %-7s %s\n' $(1) $(2);
else
  Q :=
  say :=
endif

BUILD   ?= build
JOBS    ?= $(shell nproc)
BIN     := $(BUILD)/bin
CXX     ?= g++
# g++ through ccache when it is installed (tools/setup.sh installs it): an edit of one engine
# file, a rebase or a second worktree recompiles only what changed. CCACHE= turns it off.
ifeq ($(origin CCACHE),undefined)
  CCACHE := $(shell command -v ccache 2>/dev/null)
endif
# Paths under the checkout are hashed relative to it, and the debug information names the
# checkout as "." (-fdebug-prefix-map, below), so ccache leaves the working directory out of
# its hash: a second clone or worktree (make mutants' scratch trees) reuses the cache.
export CCACHE_BASEDIR := $(CURDIR)
DEBUG_PREFIX_MAP := -fdebug-prefix-map=$(CURDIR)=.
ifeq ($(origin CXX),default)
  CXX := $(if $(CCACHE),ccache )g++
endif
OPT     ?= -O2
# Run-time dispatch (Highway), no host-specific -march: the binary must run on any x86-64.
# PCLMUL/AES are disabled so the static target stays honest without -maes -mpclmul.
DEPCFLAGS = $(shell pkg-config --cflags libhwy libpng ompi-c fmt 2>/dev/null)
DEPLIBS   = $(shell pkg-config --libs libhwy libpng ompi-c fmt 2>/dev/null)
# -g1: line tables and function names (backtraces, sanitizer reports, perf and callgrind by
# line), not the types and variables a debugger shows: a compile 20-40 % shorter than -g's,
# the link shorter still. `make CXXFLAGS="-O2 -g"` for a debugging session (the flags file
# rebuilds everything when they change).
CXXFLAGS ?= $(OPT) -g1
# The flags every build of the engine shares (the ordinary one and zephyr-smpi's). -fPIC:
# zephyr-smpi is a shared object SimGrid loads once per simulated rank, linked from the
# ordinary objects (below); -fno-semantic-interposition keeps calls within the program direct.
COMMON_CXXFLAGS = -std=c++20 -Wall -Wextra -I. -fPIC -fno-semantic-interposition $(DEBUG_PREFIX_MAP)
ALL_CXXFLAGS = $(COMMON_CXXFLAGS) $(DEPCFLAGS) $(CXXFLAGS)
LDLIBS_ALL   = $(DEPLIBS) -fopenmp -lpthread
# OpenMP (GCC's libgomp) in the files that use it: layer blocks and the host recompute run
# on every core (bitserial/blocks.h). Other files are compiled without it.
OPENMP_SRCS := $(shell grep -rl --include='*.cpp' '^ *\#pragma omp' $(or $(ROOMS),fixed bitserial hosts))
$(OPENMP_SRCS:%.cpp=$(BUILD)/obj/%.o): ALL_CXXFLAGS += -fopenmp

# Every .cpp in the library rooms is part of the engine; mains live apart.
# ROOMS / TEST_GLOB narrow a build to part of the tree (e.g. while one room is being
# rebuilt: `make BUILD=build/x ROOMS="fixed bitserial" TEST_GLOB="tests/fixed/*_test.cpp"`).
# Rooms hold folders (hosts/scene, hosts/trace, ...; docs/architecture.md): sources are
# found at any depth.
ROOMS     ?= fixed bitserial hosts
TEST_GLOB ?= tests/*/*_test.cpp
LIB_SRCS  := $(sort $(shell find $(ROOMS) -name '*.cpp') hosts/cmd/command.cpp)
LIB_SRCS  := $(filter-out hosts/cmd/main.cpp,$(LIB_SRCS))
TEST_SRCS := $(sort $(wildcard $(TEST_GLOB)))
BENCH_SRCS:= $(sort $(wildcard tools/bench/*.cpp))
EXAMPLE_SRCS := $(sort $(wildcard tools/examples/*.cpp))

LIB_OBJS  := $(LIB_SRCS:%.cpp=$(BUILD)/obj/%.o)
TEST_OBJS := $(TEST_SRCS:%.cpp=$(BUILD)/obj/%.o)
BENCH_BINS:= $(BENCH_SRCS:tools/bench/%.cpp=$(BIN)/bench_%)
EXAMPLE_BINS := $(EXAMPLE_SRCS:tools/examples/%.cpp=$(BIN)/example_%)

ZEPHYR := $(BIN)/zephyr
TESTS  := $(BIN)/zephyr_tests

# ---------------------------------------------------------------------------
.PHONY: all binaries test run bench charts future validate fuzz fuzz-smoke mutants clean help setup

help: ## List the targets
	@grep -hE '^[a-z][a-zA-Z_-]*:.*## ' Makefile | sed 's/:.*## /\t/' | \
	  awk -F'\t' '{printf "  make %-8s %s\n", $$1, $$2}'

setup: ## Install any missing Debian packages (idempotent; quick when all are there)
	$(Q)bash tools/setup.sh

all: setup ## Build the zephyr program, the tests, the benchmarks and the example programs
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) binaries

binaries: $(ZEPHYR) $(TESTS) $(BENCH_BINS) $(EXAMPLE_BINS)

# The SimGrid tests (tests/testbed) run zephyr-smpi: `make test` builds it when SimGrid's
# smpicxx is installed (tools/setup.sh installs simgrid and libsimgrid-dev).
test: setup ## Build and run every test (GoogleTest; FILTER=... to select)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(TESTS) $(ZEPHYR) $(if $(HAVE_SMPI),$(ZEPHYR_SMPI_BIN))
	$(Q)$(if $(FILTER),true,$(MAKE) --no-print-directory fuzz-smoke)
	$(Q)bash tools/test.sh $(TESTS) $(if $(FILTER),--gtest_filter='$(FILTER)')

# Defaults for `make run`: a generated 384×384 random-sphere scene, the default method.
METHOD  ?= $(DEFAULT_METHOD)
# hetero: the SIMD pass at the parent, WORKERS children shading FRAME×FRAME frames.
DEFAULT_METHOD := hetero
WORKERS ?= 2
FRAME   ?= 64
SPHERES ?= 32
SEED    ?= 1
run: setup ## Render SCENE (default: generated random spheres) with METHOD, print the cycle report
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR)
	$(Q)SCENE='$(SCENE)' METHOD='$(METHOD)' WORKERS='$(WORKERS)' FRAME='$(FRAME)' \
	  SPHERES='$(SPHERES)' SEED='$(SEED)' bash tools/run.sh

bench: setup ## Build and run the benchmarks (figures printed; medians of repeats)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR) $(BENCH_BINS)
	$(Q)bash tools/bench.sh $(BENCH_BINS)

# TESTBED=ufmg1992: the same figures in modelled 1992 seconds (docs/testbed.md), with
# dist/hetero on simulated children under SimGrid (tools/testbed/charts.sh).
charts: setup ## Run the experiment sweeps and draw the charts under docs/results/ (QUICK=1: small; TESTBED=ufmg1992: modelled)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR) $(if $(TESTBED),$(ZEPHYR_SMPI_BIN))
	$(Q)$(if $(TESTBED),TESTBED='$(TESTBED)' QUICK='$(QUICK)' bash tools/testbed/charts.sh,QUICK='$(QUICK)' bash tools/charts.sh)

# The paper's future work (docs/results.md): every method exhaustive and with a BVH, 8 → 4096
# spheres, on the 1992 testbed and two present-day ones, and where each wins with the BVH
# (tools/testbed/future.sh; REUSE=1 renders only the points docs/results/future/runs.csv lacks).
future: setup ## Modelled time of every method, exhaustive and BVH, 1992 and today, into docs/results/future/ (QUICK=1: small)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR) $(ZEPHYR_SMPI_BIN)
	$(Q)QUICK='$(QUICK)' REUSE='$(REUSE)' TESTBEDS='$(TESTBEDS)' bash tools/testbed/future.sh

# The fidelity ledger (docs/validation.md): published figures against the model, the paper's
# findings on the testbed sweep (run first, reusing the points docs/results/ already has).
validate: setup ## Write docs/validation.md and docs/results/validation.png (FRESH=1: re-render the sweep)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR) $(ZEPHYR_SMPI_BIN)
	$(Q)FRESH='$(FRESH)' bash tools/validate.sh

# The readers under libFuzzer with AddressSanitizer and UBSan (Debian's clang-14), one binary
# per target tests/fuzz/NAME_fuzz.cpp: `nff` (the NFF reader, the host tracer, the SIMD planner,
# the output pre-flight) and `readers` (the machine profile and --set, the ledger's CSVs, the
# calibrate report). `make fuzz` runs FUZZ_RUNS inputs of each (FUZZ_TARGET=NAME: one);
# `make test` runs a few seconds of each (fuzz-smoke). A target's sources are derived from
# its includes (tools/fuzz_sources.sh, not a hand-kept list), computed only when a fuzz target
# is built, and linked as an archive (a file the target never calls costs its compile only);
# the OpenMP layer blocks are left out (the planner never calls them). One object per source
# under $(BUILD)/fuzz/obj/, shared by the targets; ccache is used for clang too when present.
FUZZ_CXX  ?= $(if $(CCACHE),ccache )clang++-14
FUZZ_RUNS ?= 1000000
FUZZ_TARGETS := $(patsubst tests/fuzz/%_fuzz.cpp,%,$(wildcard tests/fuzz/*_fuzz.cpp))
FUZZ_TARGET ?= $(FUZZ_TARGETS)
FUZZ_BINS := $(FUZZ_TARGETS:%=$(BUILD)/fuzz/%_fuzz)
FUZZ_SAN  := -fno-sanitize-recover=all
# Each target's seeds: tests/fuzz/corpus (NFF scenes) for nff, tests/fuzz/NAME_corpus otherwise.
fuzz_seeds = $(if $(filter nff,$(1)),tests/fuzz/corpus,tests/fuzz/$(1)_corpus)
# A crash, timeout or slow input is written under $(BUILD)/fuzz/ (never into the tree).
FUZZ_RUN   = mkdir -p $(BUILD)/fuzz/corpus-$(1) && $(BUILD)/fuzz/$(1)_fuzz -max_len=$(if $(filter nff,$(1)),4096,65536) -timeout=10 \
             -artifact_prefix=$(BUILD)/fuzz/$(1)- $(BUILD)/fuzz/corpus-$(1) $(call fuzz_seeds,$(1))
$(BUILD)/fuzz/obj/%.o: %.cpp
	$(call say,FUZZCXX,$@)
	@mkdir -p $(@D)
	$(Q)$(FUZZ_CXX) -std=c++20 -O1 -g1 $(DEBUG_PREFIX_MAP) -I. -fsanitize=fuzzer-no-link,address,undefined $(FUZZ_SAN) \
	  -MMD -MP $$(pkg-config --cflags libhwy fmt) -c $< -o $@
# The rules that need the derived lists exist only in the sub-make `fuzz-binaries` runs
# (FUZZ_LISTS=1, the lists passed in as FUZZ_SRCS_NAME).
ifeq ($(FUZZ_LISTS),1)
define fuzz_target
$(BUILD)/fuzz/lib$(1).a: $$(FUZZ_SRCS_$(1):%.cpp=$(BUILD)/fuzz/obj/%.o)
	$$(call say,AR,$$@)
	$$(Q)rm -f $$@ && ar rcs $$@ $$^
$(BUILD)/fuzz/$(1)_fuzz: $(BUILD)/fuzz/obj/tests/fuzz/$(1)_fuzz.o $(BUILD)/fuzz/lib$(1).a
	$$(call say,FUZZLD,$$@)
	$$(Q)$$(FUZZ_CXX) -fsanitize=fuzzer,address,undefined $$(FUZZ_SAN) $$^ -o $$@ \
	  $$$$(pkg-config --libs libhwy fmt)
-include $$(FUZZ_SRCS_$(1):%.cpp=$(BUILD)/fuzz/obj/%.d) $(BUILD)/fuzz/obj/tests/fuzz/$(1)_fuzz.d
endef
$(foreach t,$(FUZZ_TARGETS),$(eval $(call fuzz_target,$(t))))
endif
fuzz_list = $(filter-out $(OPENMP_SRCS) tests/fuzz/$(1)_fuzz.cpp,$(shell bash tools/fuzz_sources.sh tests/fuzz/$(1)_fuzz.cpp))
.PHONY: fuzz-binaries
fuzz-binaries: # the fuzz targets, built in a sub-make given their derived source lists
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) FUZZ_LISTS=1 \
	  $(foreach t,$(FUZZ_TARGETS),FUZZ_SRCS_$(t)='$(call fuzz_list,$(t))') $(FUZZ_BINS)

# FUZZ_FLAGS passes libFuzzer flags: -fork=N fuzzes in N processes at once (N cores), the
# runs counted over all of them; the run stops at the first crash either way.
fuzz: ## Fuzz every reader (FUZZ_TARGET=nff|readers: one): FUZZ_RUNS inputs each (default 10^6; FUZZ_FLAGS=-fork=2 for 2 cores) under ASan+UBSan
	$(Q)$(MAKE) --no-print-directory fuzz-binaries
	$(Q)$(foreach t,$(FUZZ_TARGET),echo "fuzz: $(t)" && $(call FUZZ_RUN,$(t)) -runs=$(FUZZ_RUNS) $(FUZZ_FLAGS) &&) true

fuzz-smoke: # a few seconds of each fuzz target, part of `make test` (skipped without clang)
	$(Q)if command -v $(lastword $(FUZZ_CXX)) >/dev/null; then \
	  $(MAKE) --no-print-directory fuzz-binaries && \
	  $(foreach t,$(FUZZ_TARGETS),{ $(call FUZZ_RUN,$(t)) -max_total_time=4 2>&1 | tail -n 2; test $${PIPESTATUS[0]} -eq 0; } &&) true; \
	  else echo "fuzz-smoke: $(FUZZ_CXX) not found, skipped"; fi

# Mutation testing (tools/mutants.sh): each mutant of tools/mutants.json in a scratch copy of
# the committed tree, rebuilt and tested one at a time. MUTANTS="id ..." runs some only.
mutants: setup ## Apply each mutant of tools/mutants.json in a scratch copy, rebuild, test; print the score
	$(Q)bash tools/mutants.sh $(MUTANTS)

clean: ## Remove build/ and out/
	$(Q)rm -rf $(BUILD) out

# ---------------------------------------------------------------------------
# Rebuild everything when the compiler or flags change.
FLAGS_FILE := $(BUILD)/flags.txt
# Not ALL_CXXFLAGS: a target-specific `+= -fopenmp` (the OpenMP files) would be inherited by
# this file when one of those objects is the first to need it, and the next make would see
# other flags and rebuild everything.
FLAGS_NOW   = $(CXX) $(COMMON_CXXFLAGS) $(DEPCFLAGS) $(CXXFLAGS) $(LDLIBS_ALL) openmp: $(OPENMP_SRCS)
$(FLAGS_FILE): FORCE | $(BUILD)
	@echo '$(FLAGS_NOW)' | cmp -s - $@ || echo '$(FLAGS_NOW)' > $@
FORCE:

$(BUILD) $(BIN):
	@mkdir -p $@

$(BUILD)/obj/%.o: %.cpp $(FLAGS_FILE)
	$(call say,CXX,$<)
	@mkdir -p $(@D)
	$(Q)$(CXX) $(ALL_CXXFLAGS) -MMD -MP -c $< -o $@

$(ZEPHYR): $(LIB_OBJS) $(BUILD)/obj/hosts/cmd/main.o | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(CXX) $(ALL_CXXFLAGS) $^ -o $@ $(LDLIBS_ALL)

$(TESTS): $(LIB_OBJS) $(TEST_OBJS) | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(CXX) $(ALL_CXXFLAGS) $^ -o $@ $(LDLIBS_ALL) $(shell pkg-config --libs gtest_main)

# Bench objects are made through a pattern chain; keep them (make would delete them as
# intermediates and recompile every time).
.SECONDARY: $(BENCH_SRCS:%.cpp=$(BUILD)/obj/%.o) $(EXAMPLE_SRCS:%.cpp=$(BUILD)/obj/%.o)

# The worked programs of docs/programming.md, each build/bin/example_NAME.
$(BIN)/example_%: $(BUILD)/obj/tools/examples/%.o $(LIB_OBJS) | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(CXX) $(ALL_CXXFLAGS) $^ -o $@ $(LDLIBS_ALL)

# A benchmark may link extra libraries named in a `// LIBS: ...` line at its top.
$(BIN)/bench_%: $(BUILD)/obj/tools/bench/%.o $(LIB_OBJS) | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(CXX) $(ALL_CXXFLAGS) $^ -o $@ $(LDLIBS_ALL) \
	  $$(sed -n 's@^// LIBS: @@p' tools/bench/$*.cpp)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)

# The built-in machine profiles are data files assembled into bitserial/profile.o (.incbin, which
# the compiler's dependency list does not see): every build of that object depends on them.
PROFILE_FILES := $(wildcard bitserial/profiles/*.json)
$(BUILD)/obj/bitserial/profile.o $(BUILD)/smpi/obj/bitserial/profile.o $(BUILD)/fuzz/obj/bitserial/profile.o: $(PROFILE_FILES)

# ---------------------------------------------------------------------------
# The simulated build (docs/testbed.md): build/bin/zephyr-smpi, which smpirun runs on a platform
# file of the paper's network (hosts/testbed/platforms/). Each source is compiled once per
# compiler that must see it: only the translation units that call MPI or what SimGrid
# replaces are compiled with SimGrid's smpicxx (SMPI_ONLY_SRCS: derived below, never a kept
# list); the rest of zephyr-smpi is linked from the objects `zephyr` uses (compiled -fPIC).
# -DZEPHYR_SMPI switches hosts/farm and hosts/testbed to SimGrid's clock; smpi_prelude.h lets
# CLI11 through SMPI's exit() macro.
#
# SMPI's privatisation of globals holds for both kinds of object: smpirun loads the whole
# shared object once per simulated rank (dlopen privatisation, SimGrid's default), so every
# global of every object in it — smpicxx's or g++'s — is the rank's own. What only smpicxx
# gives is its macros: exit, sleep, usleep, nanosleep, gettimeofday, clock_gettime, getopt
# and getpid redirected to the simulation (smpi_helpers.h), MPI from SimGrid's mpi.h, and
# ZEPHYR_SMPI; a source that names any of them, or includes a header that tests ZEPHYR_SMPI
# or includes mpi.h, is compiled by smpicxx (a mention in a comment only costs a compile),
# without -g; the link strips the ordinary objects' debug information (smpirun copies the
# program once per rank).
SMPICXX    ?= smpicxx
HAVE_SMPI  := $(shell command -v $(SMPICXX) 2>/dev/null)
# smpicxx calls the compiler itself; ccache in front of it still caches (rebuilds after a
# rebase are the slow part on a shared machine).
SMPI_CC    := $(if $(CCACHE),ccache )$(SMPICXX)
SMPI_BUILD := $(BUILD)/smpi
SMPI_OPT   ?= $(OPT)
ZEPHYR_SMPI_BIN := $(BIN)/zephyr-smpi
SMPI_CXXFLAGS = $(COMMON_CXXFLAGS) \
  $(shell pkg-config --cflags libhwy libpng fmt 2>/dev/null) $(SMPI_OPT) \
  -DZEPHYR_SMPI -DSMPI_NO_OVERRIDE_MALLOC -include hosts/testbed/smpi_prelude.h
SMPI_LIBS = $(shell pkg-config --libs libhwy libpng fmt 2>/dev/null) -fopenmp -lpthread
# zephyr-smpi is for `render` (and `testbed`): the other commands (every hosts/cmd file that
# registers one) stay out of it, with the studies and generators only they use.
SMPI_COMMANDS := hosts/cmd/render.cpp hosts/cmd/testbed.cpp
SMPI_SRCS := $(filter-out $(filter-out $(SMPI_COMMANDS),$(shell grep -l '^CommandRegistration [a-zA-Z]' hosts/cmd/*.cpp)) \
               hosts/scene/gen.cpp hosts/scene/pov.cpp hosts/trace/stability.cpp hosts/methods/accuracy.cpp \
               hosts/farm/test_pattern.cpp,$(LIB_SRCS))
LPAREN := (
SMPI_HEADERS := $(shell grep -rlE '^[[:space:]]*\#[[:space:]]*(if|ifdef|ifndef|elif)[^/]*ZEPHYR_SMPI|^[[:space:]]*\#[[:space:]]*include[[:space:]]*<mpi\.h>' --include='*.h' fixed bitserial hosts)
SMPI_ONLY_SRCS := $(shell grep -lE 'ZEPHYR_SMPI|<mpi\.h>|(^|[^A-Za-z0-9_.>])(exit|sleep|usleep|nanosleep|gettimeofday|clock_gettime|getopt|getopt_long|getpid)[[:space:]]*[$(LPAREN)]$(foreach h,$(SMPI_HEADERS),|"$(h)")' \
                    $(SMPI_SRCS) hosts/cmd/main.cpp)
SMPI_OBJS := $(SMPI_ONLY_SRCS:%.cpp=$(SMPI_BUILD)/obj/%.o) \
             $(patsubst %.cpp,$(BUILD)/obj/%.o,$(filter-out $(SMPI_ONLY_SRCS),$(SMPI_SRCS)))
# The layer blocks use OpenMP here too (as in the ordinary build).
$(OPENMP_SRCS:%.cpp=$(SMPI_BUILD)/obj/%.o): SMPI_CXXFLAGS += -fopenmp

.PHONY: smpi
smpi: ## Build build/bin/zephyr-smpi (dist/hetero on a simulated 1992 network under smpirun)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(ZEPHYR_SMPI_BIN)

# Its own flags file: the ordinary build's must not rebuild this one (nor the reverse).
SMPI_FLAGS_FILE := $(SMPI_BUILD)/flags.txt
$(SMPI_FLAGS_FILE): FORCE
	@mkdir -p $(@D)
	@echo '$(SMPI_CC) $(SMPI_CXXFLAGS) $(SMPI_LIBS)' | cmp -s - $@ || echo '$(SMPI_CC) $(SMPI_CXXFLAGS) $(SMPI_LIBS)' > $@

$(SMPI_BUILD)/obj/%.o: %.cpp $(SMPI_FLAGS_FILE)
	$(call say,SMPICXX,$<)
	@mkdir -p $(@D)
	$(Q)$(SMPI_CC) $(SMPI_CXXFLAGS) -MMD -MP -c $< -o $@

$(ZEPHYR_SMPI_BIN): $(SMPI_OBJS) | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(SMPICXX) $(SMPI_CXXFLAGS) $^ -o $@ $(SMPI_LIBS)
	$(Q)strip --strip-debug $@  # smpirun copies the program once per rank

-include $(shell find $(SMPI_BUILD)/obj -name '*.d' 2>/dev/null)

# ---------------------------------------------------------------------------
# The emulator as a library (docs/programming.md, "Building a program on the library") and
# the kernel suite (docs/kernels.md). `make lib` archives the objects of fixed/ and
# bitserial/ already built for the engine (no second compile); `make install PREFIX=DIR`
# copies that archive, the public headers, the built-in profile files and a pkg-config file
# `zephyr-bitserial.pc` under DIR (DESTDIR=... for staging), and writes the list of what it
# installed (share/zephyr/installed-files) that `make uninstall PREFIX=DIR` removes. Static
# only: a shared library would need every engine file compiled a second time with -fPIC.
.PHONY: lib install uninstall kernels
PREFIX   ?= /usr/local
# PREFIX and DESTDIR reach tools/install.sh through the environment, as typed: a path with
# spaces or quotes is never split or re-parsed by a shell (the script refuses an empty or
# relative one).
export PREFIX DESTDIR
# More files `make install` puts under the prefix, "SOURCE=DEST" (DEST relative to it).
EXTRA_INSTALL ?=
LIB_NAME := zephyr-bitserial
LIB_A    := $(BUILD)/lib/lib$(LIB_NAME).a
LIB_A_OBJS = $(filter $(BUILD)/obj/fixed/% $(BUILD)/obj/bitserial/%,$(LIB_OBJS))
# The headers a program includes, with every header they include (the install test compiles
# them alone from the prefix). Not installed: bitserial/internals.h (the flag planes and the
# uncharged conversion the engine's files share) and bitserial/serial.h (the bit-serial unit
# the float operations are written on) — no public header includes either.
PUBLIC_HEADERS := fixed/format.h fixed/float.h fixed/check.h fixed/named.h fixed/reference.h \
  bitserial/multi.h bitserial/float.h bitserial/machine.h bitserial/report.h \
  bitserial/profile.h bitserial/memory.h bitserial/cost.h bitserial/kernels.h bitserial/blocks.h
# The built-in profiles' data files (PROFILE_FILES, above) are installed too.
# What a program needs besides the archive: Highway and fmt (machine.h includes Highway's
# allocator; the engine prints with fmt), nlohmann-json (report.h) when it has a .pc file,
# libgomp for the layer blocks (bitserial/blocks.cpp); Boost's headers need no flag.
PC_REQUIRES = libhwy fmt $(if $(shell pkg-config --exists nlohmann_json 2>/dev/null && echo y),nlohmann_json)
LIB_VERSION = 0.0.0-git$(shell git rev-parse --short HEAD 2>/dev/null || echo unknown)

lib: ## Build the static library build/lib/libzephyr-bitserial.a (fixed/ and bitserial/)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(LIB_A)

$(LIB_A): $(LIB_A_OBJS)
	$(call say,AR,$@)
	@mkdir -p $(@D)
	$(Q)rm -f $@ && ar rcs $@ $^

install: lib ## Install the library, headers, profiles and zephyr-bitserial.pc under PREFIX (default /usr/local)
	$(Q)LIB_A='$(LIB_A)' LIB_NAME='$(LIB_NAME)' PUBLIC_HEADERS='$(PUBLIC_HEADERS)' \
	  PROFILE_FILES='$(PROFILE_FILES)' PC_REQUIRES='$(PC_REQUIRES)' LIB_VERSION='$(LIB_VERSION)' \
	  EXTRA_INSTALL='$(EXTRA_INSTALL)' PIMEVAL_A='$(PIMEVAL_A)' bash tools/install.sh install

uninstall: ## Remove what `make install PREFIX=...` installed (its share/zephyr/installed-files)
	$(Q)bash tools/install.sh uninstall

# The kernel suite: each kernel of tools/kernels/kernels.h on every built-in profile, checked
# against plain C++ on every Highway target, timed against it; writes docs/kernels.md.
KERNELS_BIN := $(BIN)/kernels
KERNELS_FLAGS ?=
binaries: $(KERNELS_BIN)
.SECONDARY: $(BUILD)/obj/tools/kernels/kernels.o
$(KERNELS_BIN): $(BUILD)/obj/tools/kernels/kernels.o $(LIB_OBJS) | $(BIN)
	$(call say,LINK,$@)
	$(Q)$(CXX) $(ALL_CXXFLAGS) $^ -o $@ $(LDLIBS_ALL)

# The install test (tests/tools/install_test.cpp) installs the archive the test binary's
# build made and compares the out-of-tree Life with build/bin/example_life; the kernel test
# runs build/bin/kernels. All three are built with the tests (order-only: they do not
# relink the tests).
$(TESTS): | $(LIB_A) $(BIN)/example_life $(KERNELS_BIN)

kernels: setup ## Run the kernel suite on every profile (bit-exact on every target, timed); print it and write docs/kernels.md
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(KERNELS_BIN)
	$(Q)$(KERNELS_BIN) --markdown docs/kernels.md $(KERNELS_FLAGS)

# ---------------------------------------------------------------------------
# PIMeval's host API on the engine (docs/pim.md): tools/pimeval/*.cpp, a client of the public
# headers. `make install` also installs include/libpimeval.h and lib/libpimeval.a (a GNU ld
# script naming lib/libzephyr-pimeval.a — the API with the engine's objects — and the shared
# libraries it needs), so PIMbench's own Makefiles link with `-L$(PREFIX)/lib -lpimeval`
# (tools/install.sh, PIMEVAL_A). The test binary links the API's objects too (tests/pimeval/).
PIMEVAL_SRCS := $(sort $(wildcard tools/pimeval/*.cpp))
PIMEVAL_OBJS := $(PIMEVAL_SRCS:%.cpp=$(BUILD)/obj/%.o)
PIMEVAL_A    := $(BUILD)/lib/libzephyr-pimeval.a
.PHONY: pimeval-lib
pimeval-lib: ## Build build/lib/libzephyr-pimeval.a (PIMeval's API with the engine)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(PIMEVAL_A)
$(PIMEVAL_A): $(PIMEVAL_OBJS) $(LIB_A_OBJS)
	$(call say,AR,$@)
	@mkdir -p $(@D)
	$(Q)rm -f $@ && ar rcs $@ $^
$(TESTS): $(PIMEVAL_OBJS)
$(TESTS): | $(PIMEVAL_A)
lib: pimeval-lib

# PIMbench side by side (docs/pim.md): every program under PIMBENCH/PIMbench/*/PIM built with
# its own Makefile against our install (into $(BUILD)/pimbench-prefix) and, with PIMEVAL=DIR (a
# PIMeval tree whose libpimeval/ is built), against PIMeval; each run at its default and a large
# size with -v t; the measured table into docs/pim.md (tools/pimeval/pimbench.sh).
.PHONY: pimbench
pimbench: ## Run PIMbench's programs on our install (PIMBENCH=DIR, PIMEVAL=DIR for PIMeval beside); table into docs/pim.md
	$(Q)test -n '$(PIMBENCH)' || { echo "make pimbench: give PIMBENCH=DIR (a PIMbench tree)" >&2; exit 1; }
	$(Q)$(MAKE) --no-print-directory install PREFIX=$(abspath $(BUILD))/pimbench-prefix
	$(Q)bash tools/pimeval/pimbench.sh $(BUILD)/pimbench-prefix '$(PIMBENCH)' '$(PIMEVAL)'
