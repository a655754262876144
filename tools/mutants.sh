#!/usr/bin/env bash
# `make mutants`: mutation testing. Each mutant in tools/mutants.json is a small, plausible
# programmer's mistake written as data — a file, the exact original text (which must occur
# there exactly once) and its replacement. One at a time, in a scratch copy of the committed
# tree (a detached git worktree per lane, so the working tree is never touched), the mutant
# is applied, the program and the tests are rebuilt (ccache, incremental) and the tests run:
#
#   killed      the build stays green and some test fails (or the run times out);
#   survived    every test passes: the suite misses this mistake;
#   ERROR       the original text is not found (the code moved: the mutant is stale) or is
#               ambiguous, or the mutant does not compile; neither killed nor survived;
#   equivalent  listed with "equivalent": the argument why no output can change; not run,
#               not counted, but printed with its argument (never dropped silently).
#
# Which tests run: the whole suite, as `make test` runs it (a score against a
# narrower filter overstates nothing it kills but counts survivors the rest of the suite
# would kill). A mutant's "filter" (a GoogleTest filter, "*" for none in particular) names
# the suites that cover its code; they run first and every run stops at its first failure,
# so a killed mutant costs seconds; then the rest of the suite. The unmutated tree must pass
# the whole suite.
#
# What is rebuilt: every target the tests run, for every mutant, whatever its filter: the
# test binary, the zephyr program (which the MPI, durability, accuracy, charts and float
# tests run as a child), the example programs (run by their tests) and zephyr-smpi when
# SimGrid's smpicxx is installed (the SimGrid tests run it). make rebuilds what the mutated
# file feeds, and what the previous mutant's restored file fed (from ccache), so no test
# runs an unmutated program beside a mutated test binary, or the previous mutant's program.
#
# Usage: tools/mutants.sh [ID...]      (no ID: every mutant)
# Env:   MUTANTS_JSON (default tools/mutants.json); LANES (default 1): scratch copies working
#        through the list side by side; MUTANT_TIMEOUT seconds per test run (default 600);
#        JOBS make jobs per lane (default 2); KEEP=1 keeps the scratch copies;
#        MUTANTS_SCRATCH=DIR keeps them in DIR and reuses them on the next run (reset to the
#        committed tree, build/ kept), so a rerun rebuilds only what changed since.
# Prints one line per mutant, then "mutation score: K killed of N (P %)", the equivalent
# ones, the survivors and the errors; exits 1 when a mutant survives or errs.
set -uo pipefail

root=$(git rev-parse --show-toplevel)
cd "$root"
list=$(realpath "${MUTANTS_JSON:-tools/mutants.json}")
lanes=${LANES:-1}
timeout_s=${MUTANT_TIMEOUT:-600}
jobs=${JOBS:-2}
# The scratch copies' objects share the cache with the tree's: the Makefile hashes paths
# relative to the checkout (CCACHE_BASEDIR, -fdebug-prefix-map).
cxx="g++"
command -v ccache >/dev/null && cxx="ccache g++"


command -v jq >/dev/null || { echo "mutants: jq is needed (tools/setup.sh installs it)" >&2; exit 2; }
jq -e 'type == "array"' "$list" >/dev/null || { echo "mutants: $list is not a JSON array" >&2; exit 2; }

if [ -n "${MUTANTS_SCRATCH:-}" ]; then
  mkdir -p "$MUTANTS_SCRATCH" && scratch=$(realpath "$MUTANTS_SCRATCH") ||
    { echo "mutants: cannot make the scratch directory $MUTANTS_SCRATCH" >&2; exit 2; }
  rm -f "$scratch"/lane*.results
else
  scratch=$(mktemp -d "${TMPDIR:-/tmp}/zephyr-mutants.XXXXXX")
fi
cleanup() {
  jobs -p | xargs -r kill 2>/dev/null
  if [ "${KEEP:-0}" != 1 ] && [ -z "${MUTANTS_SCRATCH:-}" ]; then
    for ((l = 0; l < lanes; ++l)); do git worktree remove --force "$scratch/tree$l" >/dev/null 2>&1; done
    rm -rf "$scratch"
  fi
}
trap cleanup EXIT

examples=$(ls tools/examples/*.cpp 2>/dev/null | sed 's|tools/examples/\(.*\)\.cpp|build/bin/example_\1|' | paste -sd' ' -)
smpi=""
command -v smpicxx >/dev/null && smpi=build/bin/zephyr-smpi
targets="build/bin/zephyr_tests build/bin/zephyr $examples $smpi"
build() {  # $1: tree
  make -C "$1" --no-print-directory -j"$jobs" CXX="$cxx" $targets >"$1.build.log" 2>&1
}
runtests() {  # $1: tree, $2: gtest filter; the status of the run (stops at the first failure)
  (cd "$1" && timeout -k 10 "$timeout_s" build/bin/zephyr_tests --gtest_brief=1 --gtest_fail_fast \
    --gtest_filter="$2" >"$1.test.log" 2>&1)
}
# A mutant's run: its own suites first (where a kill is most likely: a killed mutant costs
# seconds), then the rest of the whole suite. Killed means a test in either failed. Never
# Mutants.*: it checks the list against the committed sources, and a mutated source lacks its
# original by construction, so it would "kill" every mutant.
runmutant() {  # $1: tree, $2: the mutant's filter
  runtests "$1" "$2-Mutants.*" || return
  [ "$2" = "*" ] && return 0
  runtests "$1" "*-$2:Mutants.*"
}

ids=("$@")
[ ${#ids[@]} -eq 0 ] && mapfile -t ids < <(jq -r '.[].id' "$list")
echo "mutants: ${#ids[@]} mutants of $list on $(git rev-parse --short HEAD) (committed tree), $lanes lane(s), scratch $scratch"

# Scratch trees, built unmutated (in parallel; ccache makes this mostly linking).
for ((l = 0; l < lanes; ++l)); do
  if [ -d "$scratch/tree$l" ]; then  # reused (MUTANTS_SCRATCH): back to the committed tree
    git -C "$scratch/tree$l" checkout -q --detach --force "$(git rev-parse HEAD)" &&
      git -C "$scratch/tree$l" clean -q -fd -e build ||
      { echo "mutants: cannot reset the scratch worktree $scratch/tree$l" >&2; exit 2; }
  else
    git worktree prune  # a scratch folder deleted by hand leaves its worktree registered
    git worktree add --detach "$scratch/tree$l" HEAD >/dev/null 2>&1 ||
      { echo "mutants: cannot make a scratch worktree in $scratch" >&2; exit 2; }
  fi
  build "$scratch/tree$l" &
done
for ((l = 0; l < lanes; ++l)); do
  wait -n || { tail -20 "$scratch"/tree*.build.log; echo "mutants: the unmutated tree does not build" >&2; exit 2; }
done

# The baseline must pass the whole suite, else a "kill" would mean nothing.
echo "mutants: baseline run of the whole suite"
if ! runtests "$scratch/tree0" "*"; then
  grep -E '^\[  FAILED  \]' "$scratch/tree0.test.log" | head -20
  echo "mutants: the unmutated tree fails its tests; fix that first" >&2
  exit 2
fi

# One lane: its share of the mutants in order; one result line each (tab-separated:
# outcome, id, file, what, detail) into $scratch/lane$l.results.
run_lane() {
  local l=$1; shift
  local tree=$scratch/tree$l out=$scratch/lane$l.results
  : >"$out"
  for id in "$@"; do
    local m file what filter count start status secs detail
    m=$(jq -c --arg id "$id" '.[] | select(.id == $id)' "$list")
    if [ -z "$m" ]; then printf 'ERROR\t%s\t-\t-\tno such mutant\n' "$id" >>"$out"; continue; fi
    file=$(jq -r .file <<<"$m"); what=$(jq -r .what <<<"$m"); filter=$(jq -r .filter <<<"$m")
    if [ -n "$(jq -r '.equivalent // empty' <<<"$m")" ]; then
      printf 'equivalent\t%s\t%s\t%s\t%s\n' "$id" "$file" "$what" "$(jq -r .equivalent <<<"$m")" >>"$out"
      continue
    fi
    # The original must occur exactly once (literal text, may span lines).
    count=$(ORIG=$(jq -r .original <<<"$m") perl -0777 -ne '$o = $ENV{ORIG}; $n = () = /\Q$o\E/g; print $n' "$tree/$file" 2>/dev/null)
    if [ "${count:-0}" != 1 ]; then
      detail=$([ "${count:-0}" = 0 ] && echo "original text not found (stale: the code moved)" || echo "original text occurs $count times")
      printf 'ERROR\t%s\t%s\t%s\t%s\n' "$id" "$file" "$what" "$detail" >>"$out"
      continue
    fi
    cp "$tree/$file" "$tree.original"
    ORIG=$(jq -r .original <<<"$m") REPL=$(jq -r .replacement <<<"$m") \
      perl -0777 -i -pe 'BEGIN { $o = $ENV{ORIG}; $r = $ENV{REPL} } s/\Q$o\E/$r/' "$tree/$file"
    start=$(date +%s)
    if ! build "$tree"; then
      printf 'ERROR\t%s\t%s\t%s\t%s\n' "$id" "$file" "$what" "the mutant does not compile" >>"$out"
    else
      runmutant "$tree" "$filter"
      status=$?
      secs=$(( $(date +%s) - start ))
      if [ $status -eq 0 ]; then
        printf 'survived\t%s\t%s\t%s\t%ds\n' "$id" "$file" "$what" "$secs" >>"$out"
      else
        detail=$(grep -m1 -E '^\[  FAILED  \]' "$tree.test.log")
        if [ $status -eq 124 ] || [ $status -eq 137 ]; then detail="timed out after ${timeout_s}s"; fi
        printf 'killed\t%s\t%s\t%s\t%ds; %s\n' "$id" "$file" "$what" "$secs" "${detail:-status $status}" >>"$out"
      fi
    fi
    tail -1 "$out" | awk -F'\t' '{ printf "%-10s %-34s %s (%s)\n", $1, $2, $4, $5 }'
    cp "$tree.original" "$tree/$file"  # restore (the next build brings its objects back from ccache)
  done
}

for ((l = 0; l < lanes; ++l)); do
  share=()
  for ((i = l; i < ${#ids[@]}; i += lanes)); do share+=("${ids[$i]}"); done
  run_lane "$l" "${share[@]}" &
done
wait

results=$(cat "$scratch"/lane*.results)
killed=$(grep -c '^killed' <<<"$results")
survived=$(grep -c '^survived' <<<"$results")
total=$((killed + survived))
echo
echo "mutation score: $killed killed of $total ($(( total ? 100 * killed / total : 0 )) %)" \
     "[$(grep -c '^equivalent' <<<"$results") equivalent, $(grep -c '^ERROR' <<<"$results") errors, not counted]"
section() {  # $1: outcome, $2: heading
  grep "^$1" <<<"$results" | awk -F'\t' -v h="$2" 'NR == 1 { print h } { printf "  %s (%s): %s — %s\n", $2, $3, $4, $5 }'
}
section equivalent "equivalent (not counted):"
section survived "survivors:"
section ERROR "errors (not counted):"
[ "$survived" -eq 0 ] && ! grep -q '^ERROR' <<<"$results"
