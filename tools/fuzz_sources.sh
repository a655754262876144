#!/usr/bin/env bash
# tools/fuzz_sources.sh — the sources a fuzz target links, derived from its includes (issue 41:
# never a hand-kept list). From the target's .cpp, every `#include "x.h"` of the tree is
# followed; a header brings its definitions: its own x.cpp and every .cpp of its folder that
# includes it (multi.h's operations live in multi.cpp, mesh.cpp, reductions.cpp,
# transfer.cpp); each is followed in turn until nothing new appears. Prints the .cpp files,
# one a line, sorted. The Makefile links them as an archive, so a file the target never calls
# costs its compile only.
#
#   tools/fuzz_sources.sh tests/fuzz/nff_fuzz.cpp
set -euo pipefail
cd "$(dirname "$0")/.."
declare -A includes=() definers=() seen=()
# Every quoted include of the tree, read once: "file:header".
while IFS=: read -r file header; do
  includes[$file]+="$header "
  if [[ "$file" == *.cpp && "${file%/*}" == "${header%/*}" ]]; then
    definers[$header]+="$file "
  fi
done < <(grep -rH --include='*.cpp' --include='*.h' -o '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^"]*"' \
           fixed bitserial hosts tests/fuzz tools 2>/dev/null |
         sed 's/:[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)"/:\1/')
queue=("$@")
sources=()
while ((${#queue[@]})); do
  f="${queue[0]}"
  queue=("${queue[@]:1}")
  [[ -n "${seen[$f]:-}" || ! -f "$f" ]] && continue
  seen[$f]=1
  [[ "$f" == *.cpp ]] && sources+=("$f")
  for inc in ${includes[$f]:-}; do
    queue+=("$inc")
    if [[ "$inc" == *.h ]]; then
      own="${inc%.h}.cpp"
      [[ -f "$own" ]] && queue+=("$own")
      for cpp in ${definers[$inc]:-}; do queue+=("$cpp"); done
    fi
  done
done
printf '%s\n' "${sources[@]}" | sort
