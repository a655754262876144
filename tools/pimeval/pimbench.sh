#!/usr/bin/env bash
# tools/pimeval/pimbench.sh PREFIX PIMBENCH [PIMEVAL] — what `make pimbench` runs (docs/pim.md):
# every program PIMBENCH/PIMbench/*/PIM built with its own Makefile against our install at
# PREFIX and, when PIMEVAL (a PIMeval tree whose libpimeval/ is built: `make -C libpimeval`) is
# given, against PIMeval too; each run with `-v t` at its default size and at a large one; the
# table (verification, modelled kernel and copy ms, wall seconds) printed and written into
# docs/pim.md between its "pimbench" markers. Scratch copies under build/pimbench: nothing is
# written under PIMBENCH. Every figure is measured in this run.
set -euo pipefail
if [ $# -lt 2 ]; then echo "usage: $0 PREFIX PIMBENCH [PIMEVAL]" >&2; exit 2; fi
prefix=$(cd "$1" && pwd) bench=$(cd "$2" && pwd) pimeval=${3:-}
[ -f "$bench/Makefile.common" ] || { echo "pimbench: $bench/Makefile.common not found" >&2; exit 1; }
if [ -n "$pimeval" ]; then
  pimeval=$(cd "$pimeval" && pwd)
  [ -f "$pimeval/libpimeval/lib/libpimeval.a" ] ||
    { echo "pimbench: $pimeval/libpimeval/lib/libpimeval.a not found (make -C $pimeval/libpimeval)" >&2; exit 1; }
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
scratch=$root/build/pimbench
rm -rf "$scratch" && mkdir -p "$scratch"

# The large size of each program: 2^20 elements where it takes a length, else its default.
large() {
  case $1 in
    vec-add|axpy|prefix-sum) echo "-l 1048576" ;;
    gemv) echo "-r 1048576" ;;
    kmeans) echo "-p 1048576" ;;
    *) echo "" ;;
  esac
}

# Builds every program of $bench against library $2 into $scratch/$1.
build() {
  local name=$1 lib=$2
  cp -r "$bench" "$scratch/$name"
  for mk in "$scratch/$name"/PIMbench/*/PIM/Makefile; do
    make --no-print-directory -s -C "$(dirname "$mk")" LIBPIMEVAL_PATH="$lib" >/dev/null
  done
}
build zephyr "$prefix"
[ -n "$pimeval" ] && build pimeval "$pimeval/libpimeval"

# One run: prints "ok|FAIL kernelMs copyMs wallSeconds".
run() {
  local lib=$1 prog=$2 args=$3 dir out start end status verdict kernel copy
  dir=$(dirname "$(ls "$scratch/$lib"/PIMbench/"$prog"/PIM/*.out)")
  start=$(date +%s.%N)
  set +e
  # PIMeval models its default target (BANK_LEVEL, bit-parallel) unless told: BitSIMD-V here.
  out=$(cd "$dir" && PIMEVAL_SIM_TARGET=PIM_DEVICE_BITSIMD_V \
        ./"$(basename "$(ls "$dir"/*.out)")" -v t $args 2>&1)
  status=$?
  set -e
  end=$(date +%s.%N)
  verdict=ok
  if [ $status -ne 0 ] || grep -qE "Wrong|wrong answer|Mismatch|Abort|PIM-Error|Incorrect" <<<"$out"; then
    verdict=FAIL; fi
  if [ "$lib" = zephyr ]; then
    kernel=$(sed -n 's/^Modelled time: .*, \([0-9.]*\) ms kernel$/\1/p' <<<"$out")
    copy=$(sed -n 's/^Modelled time: .* ms in all, \([0-9.]*\) ms of it.*/\1/p' <<<"$out")
  else
    kernel=$(awk '/^PIM Command Stats:/{c=1} c && /TOTAL ---------/{print $5; exit}' <<<"$out")
    copy=$(awk '/^Data Copy Stats:/{c=1} c && /TOTAL ---------/{print $6; exit}' <<<"$out")
  fi
  printf '%s %s %s %.2f\n' "$verdict" "${kernel:-?}" "${copy:-?}" "$(echo "$end - $start" | bc)"
}

table=$scratch/table.md
{
  echo "Measured by \`make pimbench\` on $(date -u +%Y-%m-%d), $(nproc) cores; modelled times on"
  echo "the default device (4 ranks x 128 banks x 32 subarrays x 8192 columns, 1024 rows)."
  echo
  if [ -n "$pimeval" ]; then
    echo "| program | args | ours: check | ours: kernel ms | ours: copy ms | ours: wall s | PIMeval: check | PIMeval: kernel ms | PIMeval: copy ms | PIMeval: wall s | kernel ratio |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
  else
    echo "| program | args | check | kernel ms | copy ms | wall s |"
    echo "|---|---|---|---|---|---|"
  fi
} > "$table"
for mk in "$bench"/PIMbench/*/PIM/Makefile; do
  prog=$(basename "$(dirname "$(dirname "$mk")")")
  for args in "" "$(large "$prog")"; do
    [ -z "$args" ] && [ "$args" != "" ] && continue
    read -r v k c w < <(run zephyr "$prog" "$args")
    if [ -n "$pimeval" ]; then
      read -r pv pk pc pw < <(run pimeval "$prog" "$args")
      ratio=$(awk -v a="$k" -v b="$pk" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "?" }')
      echo "| $prog | ${args:-default} | $v | $k | $c | $w | $pv | $pk | $pc | $pw | $ratio |" >> "$table"
    else
      echo "| $prog | ${args:-default} | $v | $k | $c | $w |" >> "$table"
    fi
    [ -z "$(large "$prog")" ] && break
  done
done
cat "$table"
doc=$root/docs/pim.md
if grep -q '<!-- pimbench:begin -->' "$doc"; then
  awk -v t="$table" '/<!-- pimbench:begin -->/{print; while ((getline l < t) > 0) print l; skip=1; next}
                     /<!-- pimbench:end -->/{skip=0} !skip' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
  echo "wrote the table into $doc"
fi
