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
ifeq ($(origin CXX),default)
  CXX := g++
endif
OPT     ?= -O2
# Run-time dispatch (Highway), no host-specific -march: the binary must run on any x86-64.
# PCLMUL/AES are disabled so the static target stays honest without -maes -mpclmul.
DEPCFLAGS = $(shell pkg-config --cflags libhwy libpng ompi-c fmt 2>/dev/null)
DEPLIBS   = $(shell pkg-config --libs libhwy libpng ompi-c fmt 2>/dev/null)
CXXFLAGS ?= $(OPT) -g
# The flags every build of the engine shares (the ordinary one and zephyr-smpi's).
COMMON_CXXFLAGS = -std=c++20 -Wall -Wextra -I.
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

# The NFF reader under libFuzzer with AddressSanitizer and UBSan (Debian's clang-14).
# `make fuzz` runs FUZZ_RUNS inputs; `make test` runs a few seconds of it (fuzz-smoke).
# One object per source under $(BUILD)/fuzz/obj/ (built -j, again only when a source or a
# header it includes changes); ccache is used for clang too when CXX names it.
FUZZ_CXX  ?= $(if $(filter ccache,$(firstword $(CXX))),ccache )clang++-14
FUZZ_RUNS ?= 1000000
FUZZ_BIN  := $(BUILD)/fuzz/nff_fuzz
# The reader, the host tracer and the SIMD planner (with the arithmetic, the array and the
# program it measures on one virtual PE); not the pass itself, which runs the program on
# every pixel and is far too slow per input, nor the OpenMP layer blocks (bitserial/blocks.cpp)
# the planner never calls.
FUZZ_SRCS := tests/fuzz/nff_fuzz.cpp hosts/scene/nff.cpp hosts/scene/scene.cpp hosts/io/output_file.cpp hosts/io/test_seam.cpp \
             hosts/scene/geometry.cpp hosts/trace/tracer.cpp hosts/trace/bvh.cpp hosts/trace/sphere_kernels.cpp \
             $(filter-out $(OPENMP_SRCS),$(wildcard fixed/*.cpp bitserial/*.cpp)) \
             hosts/trace/exact.cpp \
             $(addprefix hosts/simd/,options.cpp plan.cpp program.cpp audit.cpp bounds.cpp ops.cpp sphere.cpp sphere_float.cpp ellipsoid.cpp polygon.cpp cone.cpp)
FUZZ_OBJS := $(FUZZ_SRCS:%.cpp=$(BUILD)/fuzz/obj/%.o)
FUZZ_SAN  := -fno-sanitize-recover=all
# A crash, timeout or slow input is written under $(BUILD)/fuzz/ (never into the tree).
FUZZ_RUN   = mkdir -p $(BUILD)/fuzz/corpus && $(FUZZ_BIN) -max_len=4096 -timeout=10 -artifact_prefix=$(BUILD)/fuzz/ \
             $(BUILD)/fuzz/corpus tests/fuzz/corpus
$(BUILD)/fuzz/obj/%.o: %.cpp
	$(call say,FUZZCXX,$@)
	@mkdir -p $(@D)
	$(Q)$(FUZZ_CXX) -std=c++20 -O1 -g -I. -fsanitize=fuzzer-no-link,address,undefined $(FUZZ_SAN) \
	  -MMD -MP $$(pkg-config --cflags libhwy fmt) -c $< -o $@
$(FUZZ_BIN): $(FUZZ_OBJS)
	$(call say,FUZZLD,$@)
	$(Q)$(FUZZ_CXX) -fsanitize=fuzzer,address,undefined $(FUZZ_SAN) $^ -o $@ \
	  $$(pkg-config --libs libhwy fmt)
-include $(FUZZ_OBJS:.o=.d)

# FUZZ_FLAGS passes libFuzzer flags: -fork=N fuzzes in N processes at once (N cores), the
# runs counted over all of them; the run stops at the first crash either way.
fuzz: ## Fuzz the NFF reader, tracer, SIMD planner and output pre-flight: FUZZ_RUNS inputs (default 10^6; FUZZ_FLAGS=-fork=2 for 2 cores) under ASan+UBSan
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(FUZZ_BIN)
	$(Q)$(FUZZ_RUN) -runs=$(FUZZ_RUNS) $(FUZZ_FLAGS)

fuzz-smoke: # a few seconds of fuzzing, part of `make test` (skipped without clang)
	$(Q)if command -v $(lastword $(FUZZ_CXX)) >/dev/null; then \
	  $(MAKE) --no-print-directory -j$(JOBS) $(FUZZ_BIN) && \
	  $(FUZZ_RUN) -max_total_time=5 2>&1 | tail -n 3; test $${PIPESTATUS[0]} -eq 0; \
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
FLAGS_NOW   = $(CXX) $(ALL_CXXFLAGS) $(LDLIBS_ALL)
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
# The simulated build (docs/testbed.md): the same sources compiled a second time with
# SimGrid's smpicxx into build/bin/zephyr-smpi, which smpirun runs on a platform file of the
# paper's network (hosts/testbed/platforms/). -DZEPHYR_SMPI switches hosts/testbed to
# SimGrid's clock; smpi_prelude.h lets CLI11 through SMPI's exit() macro. No -g: smpirun
# copies the program once per simulated rank.
SMPICXX    ?= smpicxx
HAVE_SMPI  := $(shell command -v $(SMPICXX) 2>/dev/null)
# smpicxx calls the compiler itself; ccache in front of it still caches (rebuilds after a
# rebase are the slow part on a shared machine).
SMPI_CC    := $(if $(shell command -v ccache 2>/dev/null),ccache )$(SMPICXX)
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
SMPI_OBJS := $(SMPI_SRCS:%.cpp=$(SMPI_BUILD)/obj/%.o) $(SMPI_BUILD)/obj/hosts/cmd/main.o
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
PREFIX_ABS = $(abspath $(PREFIX))
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
INSTALL_ROOT = $(DESTDIR)$(PREFIX_ABS)
INSTALLED_LIST = $(INSTALL_ROOT)/share/zephyr/installed-files

lib: ## Build the static library build/lib/libzephyr-bitserial.a (fixed/ and bitserial/)
	$(Q)$(MAKE) --no-print-directory -j$(JOBS) $(LIB_A)

$(LIB_A): $(LIB_A_OBJS)
	$(call say,AR,$@)
	@mkdir -p $(@D)
	$(Q)rm -f $@ && ar rcs $@ $^

install: lib ## Install the library, headers, profiles and zephyr-bitserial.pc under PREFIX (default /usr/local)
	$(Q)set -e; root='$(INSTALL_ROOT)'; list=$$(mktemp); \
	  for h in $(PUBLIC_HEADERS); do \
	    install -D -m 644 $$h "$$root/include/zephyr/$$h"; echo "include/zephyr/$$h" >> $$list; done; \
	  install -D -m 644 $(LIB_A) "$$root/lib/lib$(LIB_NAME).a"; echo "lib/lib$(LIB_NAME).a" >> $$list; \
	  for p in $(PROFILE_FILES); do \
	    install -D -m 644 $$p "$$root/share/zephyr/profiles/$$(basename $$p)"; \
	    echo "share/zephyr/profiles/$$(basename $$p)" >> $$list; done; \
	  mkdir -p "$$root/lib/pkgconfig"; \
	  printf '%s\n' 'prefix=$(PREFIX_ABS)' 'includedir=$${prefix}/include/zephyr' \
	    'libdir=$${prefix}/lib' 'profilesdir=$${prefix}/share/zephyr/profiles' '' \
	    'Name: $(LIB_NAME)' \
	    'Description: The emulated WaveTracer Zephyr bit-serial SIMD array and its MultiC-like API' \
	    'Version: $(LIB_VERSION)' 'Requires: $(PC_REQUIRES)' \
	    'Libs: -L$${libdir} -l$(LIB_NAME) -lgomp -lpthread' 'Cflags: -I$${includedir}' \
	    > "$$root/lib/pkgconfig/$(LIB_NAME).pc"; \
	  echo "lib/pkgconfig/$(LIB_NAME).pc" >> $$list; \
	  mkdir -p "$$(dirname '$(INSTALLED_LIST)')"; mv $$list '$(INSTALLED_LIST)'; chmod 644 '$(INSTALLED_LIST)'; \
	  echo "installed $$(wc -l < '$(INSTALLED_LIST)') files under $$root (list: $(INSTALLED_LIST))"
	$(Q)bash tools/pimeval/install.sh '$(INSTALL_ROOT)' '$(PREFIX_ABS)' '$(INSTALLED_LIST)' $(PIMEVAL_A)

uninstall: ## Remove what `make install PREFIX=...` installed (its share/zephyr/installed-files)
	$(Q)set -e; root='$(INSTALL_ROOT)'; \
	  if [ ! -f '$(INSTALLED_LIST)' ]; then echo "uninstall: nothing installed under $$root ($(INSTALLED_LIST) not found)" >&2; exit 1; fi; \
	  while read -r f; do rm -f "$$root/$$f"; done < '$(INSTALLED_LIST)'; rm -f '$(INSTALLED_LIST)'; \
	  for d in include/zephyr/fixed include/zephyr/bitserial include/zephyr share/zephyr/profiles share/zephyr lib/pkgconfig; do \
	    rmdir "$$root/$$d" 2>/dev/null || true; done; \
	  echo "removed the installed files under $$root"


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
# (tools/pimeval/install.sh). The test binary links the API's objects too (tests/pimeval/).
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
