#!/usr/bin/env bash
# tools/testbed/future.sh — `make future` (docs/results.md, "The paper's future work"): the
# paper's §8 next step, heterogeneity combined with an acceleration structure and on other
# architectures. For each testbed (ufmg1992: the 1992 system; today-zephyr: the Zephyr behind a
# present-day cluster; today-pim: a present-day processing-in-DRAM array on the memory bus;
# docs/testbed.md, docs/present-day.md) and each host tracer (--accel none: the paper's
# exhaustive one; --accel bvh: a hierarchy), modelled seconds of seq, simd, dist, hetero (K
# children, frames F) and array (all rays on the array) over random spheres 8 → 4096 at
# 384×384; where each method wins over objects × Ethernet bandwidth with the BVH; the summary
# of who wins at each count. seq/simd/array come from `zephyr render --testbed`; dist/hetero
# from build/bin/zephyr-smpi under smpirun (tools/testbed/simrun.sh). Every figure is read from
# the JSON reports. Output: docs/results/future/ (CSV + PNG).
#
# Environment: TESTBEDS (default "ufmg1992 today-zephyr today-pim"), QUICK=1 (64×64, few
#   points), OUT=dir, ZEPHYR / ZEPHYR_SMPI, REUSE=1 (keep OUT/runs.csv and render only the
#   points it lacks: the model is deterministic).
set -euo pipefail
# One block, read before it runs: editing this file during a long sweep changes nothing.
{

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
abspath() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
TESTBEDS=${TESTBEDS:-ufmg1992 today-zephyr today-pim}
ZEPHYR=$(abspath "${ZEPHYR:-$ROOT/build/bin/zephyr}")
ZEPHYR_SMPI=$(abspath "${ZEPHYR_SMPI:-$ROOT/build/bin/zephyr-smpi}")
OUT=$(abspath "${OUT:-$ROOT/docs/results/future}")
GP=$ROOT/tools/charts
SIMRUN=$ROOT/tools/testbed/simrun.sh

if [ -n "${QUICK:-}" ] && [ "${QUICK}" != 0 ]; then
  SIZE=64 COUNTS="8 32" K=2 FRAME=16 MAP_COUNTS="8 32" ARRAY_2K_MAX=32 SENS_COUNTS="32"
  MAP_BW_ufmg1992="1e6 1e7" MAP_BW_today="1e9 2.5e10"
else
  SIZE=384 COUNTS="8 32 64 128 256 512 1024 2048 4096" K=8 FRAME=32 MAP_COUNTS="8 128 1024 4096"
  ARRAY_2K_MAX=1024 SENS_COUNTS="128 1024"
  MAP_BW_ufmg1992="1e5 1e6 1e7 1e8" MAP_BW_today="1e8 1e9 2.5e10 1e11"
fi
SEED=${SEED:-1} NAME=future
ACCELS="none bvh"
. "$ROOT/tools/testbed/sweep.sh"
say "testbeds {$TESTBEDS}: ${SIZE}x${SIZE}, objects {$COUNTS}, $K children, frames $FRAME"
make_scenes $COUNTS $MAP_COUNTS

RUNS=$OUT/runs.csv
HEADER="testbed,method,accel,objects,children,frame,ethernet_bps,model_s,array_s,host_s,wall_s"
if [ "${REUSE:-0}" = 0 ] || [ ! -f "$RUNS" ] || [ "$(head -1 "$RUNS")" != "$HEADER" ]; then
  echo "$HEADER" >"$RUNS"
fi
# pick TESTBED METHOD ACCEL OBJECTS CHILDREN BW COLUMN: the first matching row's value, or NaN.
pick() {
  awk -F, -v t="$1" -v m="$2" -v a="$3" -v n="$4" -v k="$5" -v bw="$6" -v c="$7" \
    'NR > 1 && $1 == t && $2 == m && $3 == a && $4 == n && $5 == k && $7 == bw { print $c; found = 1; exit }
     END { if (!found) print "NaN" }' "$RUNS"
}
MODEL=8
# One row of runs.csv (on standard output) from a report. SECTION is the report's testbed section (.testbed, or
# .alsoTestbeds[I] for a testbed priced on the same render). array_s: the array's seconds with
# its host link (seq/simd/array: SECTION.array; dist/hetero: the parent's array pass); host_s:
# the host's modelled seconds (seq/simd/array) or the children's mean busy seconds (dist/hetero).
row() {  # testbed method accel objects children frame bw wall report section
  jq -r --arg t "$1" --arg m "$2" --arg a "$3" --arg n "$4" --arg k "$5" --arg f "$6" --arg bw "$7" --arg w "$8" "
    ${10} as \$s |
    [\$t, \$m, \$a, \$n, \$k, \$f, \$bw, \$s.modelledSeconds,
     (if .distributed then \$s.parent.arrayPassSeconds
      else ((\$s.array.seconds // 0) + (\$s.array.linkSeconds // 0)) end),
     (if .distributed then ([\$s.children[] | .busySeconds // 0] | add / length)
      else \$s.host.seconds end),
     \$w] | @csv" "$9" | tr -d '"'
}
array_of() { "$ZEPHYR" testbed show "$1" | jq -r '.arrayProfile'; }
declare -A ARRAY_OF
for t in $TESTBEDS; do ARRAY_OF[$t]=$(array_of "$t"); done
# The array method on a testbed whose PE memory cannot hold its bounce program (today-pim's
# 1024 rows a subarray; the program needs 2048 bits): run with the memory doubled, as method
# "array-2k" (the same row access cost: an assumption), up to ARRAY_2K_MAX objects.
ARRAY_2K_SET=(--set internalBitsPerPe=1536 --set externalBitsPerPe=512)
array_method() {  # testbed: "array", or "array-2k" where the bounce program needs more memory
  [ "${ARRAY_OF[$1]}" = pim-bitsimd-v-bank ] && echo array-2k || echo array
}
# seq/simd/array: one render priced on every testbed of the sweep that shares its array
# (--also-testbed): their counted work is the same.
local_run() {  # testbed method accel objects
  local r=$WORK/r.json t0=$SECONDS t=$1 m=$2 set=() peers=() also=()
  [ "$(pick "$t" "$m" "$3" "$4" 0 0 $MODEL)" = NaN ] || return 0  # REUSE=1: already rendered
  if [ "$m" = array-2k ]; then
    m=array set=("${ARRAY_2K_SET[@]}")
    [ "$4" -le "$ARRAY_2K_MAX" ] || return 0
  else
    for p in $TESTBEDS; do
      if [ "$p" != "$t" ] && [ "${ARRAY_OF[$p]}" = "${ARRAY_OF[$t]}" ] &&
        [ "$(pick "$p" "$2" "$3" "$4" 0 0 $MODEL)" = NaN ]; then
        peers+=("$p") also+=(--also-testbed "$p")
      fi
    done
  fi
  "$ZEPHYR" render --no-progress --method "$m" --accel "$3" "$(scene "$4")" --testbed "$t" \
    "${also[@]}" "${set[@]}" --report "$r" >"$WORK/log" 2>&1 || { say "failed: $*"; tail -n 3 "$WORK/log" >&2; return 0; }
  row "$t" "$2" "$3" "$4" 0 0 0 "$(( SECONDS - t0 ))" "$r" .testbed >>"$RUNS"
  for i in "${!peers[@]}"; do
    row "${peers[$i]}" "$2" "$3" "$4" 0 0 0 0 "$r" ".alsoTestbeds[$i]" >>"$RUNS"
  done
}
sim_run() {  # testbed method accel objects [ethernet_bps]
  local r=$WORK/r.json t0=$SECONDS bw=${5:-0}
  [ "$(pick "$1" "$2" "$3" "$4" "$K" "$bw" $MODEL)" = NaN ] || return 0
  local plat=(--testbed "$1")
  if [ "$bw" != 0 ]; then
    "$ZEPHYR" testbed platform --testbed "$1" --children "$K" --ethernet-bps "$bw" --out "$WORK/p.xml" --hostfile "$WORK/h"
    plat=(--platform "$WORK/p.xml" --hostfile "$WORK/h")
  fi
  rm -f "$r"
  bash "$SIMRUN" --children "$K" "${plat[@]}" --zephyr "$ZEPHYR_SMPI" -- render --no-progress \
    --method "$2" --accel "$3" "$(scene "$4")" --frame "$FRAME" --testbed "$1" --report "$r" >"$WORK/log" 2>&1 ||
    { say "failed: $*"; tail -n 3 "$WORK/log" >&2; return 0; }
  row "$1" "$2" "$3" "$4" "$K" "$FRAME" "$bw" "$(( SECONDS - t0 ))" "$r" .testbed >>"$RUNS"
}

# The testbed's own Ethernet bandwidth (bit/s); a map point at it is the sweep's (bw 0).
own_bw() { "$ZEPHYR" testbed show "$1" | jq -r '.ethernetBandwidth.value'; }
map_bw() { awk -v a="$1" -v b="$2" 'BEGIN { print (a + 0 == b + 0) ? 0 : a }'; }

# ---- The sweep -------------------------------------------------------------------------------
for t in $TESTBEDS; do
  for n in $COUNTS; do
    for a in $ACCELS; do
      for m in seq simd; do local_run "$t" "$m" "$a" "$n"; done
      for m in dist hetero; do sim_run "$t" "$m" "$a" "$n"; done
    done
    # All rays on the array: its array passes are the same with either host tracer, whose
    # part (the uncertain rays, ~1 %) takes the BVH.
    local_run "$t" "$(array_method "$t")" bvh "$n"
    say "$t: $n objects done (${SECONDS} s)"
  done
  bws=MAP_BW_${t%%-*} bw0=$(own_bw "$t")
  for bw in ${!bws}; do for n in $MAP_COUNTS; do
    b=$(map_bw "$bw" "$bw0")
    sim_run "$t" dist bvh "$n" "$b"; sim_run "$t" hetero bvh "$n" "$b"
  done; done
  say "$t: map done (${SECONDS} s)"
done

# ---- How the answer moves: the present-day testbeds' assumed values halved and doubled -----
# (docs/present-day.md). With the BVH, at SENS_COUNTS objects: the host's speed (--host-ops:
# the calibrated core has one rate), the array's clock (--array-clock), the message latency
# and the MPI poll, each × 0.5 and × 2. dist/hetero are simulated again on a platform so
# changed (sensitivity_runs.csv); seq/simd/array are additive (array + host seconds), so
# their figures scale: the host's seconds by 1/f, the array's (its link priced in its cycles)
# by 1/f.
SENS=$OUT/sensitivity_runs.csv
SENS_HEADER="variation,factor,$HEADER"
if [ "${REUSE:-0}" = 0 ] || [ ! -f "$SENS" ] || [ "$(head -1 "$SENS")" != "$SENS_HEADER" ]; then
  echo "$SENS_HEADER" >"$SENS"
fi
VARIATIONS="host array latency poll"
sens_pick() {  # variation factor testbed method objects: model_s or NaN
  awk -F, -v v="$1" -v f="$2" -v t="$3" -v m="$4" -v n="$5" \
    'NR > 1 && $1 == v && $2 == f && $3 == t && $4 == m && $6 == n { print $10; found = 1; exit }
     END { if (!found) print "NaN" }' "$SENS"
}
sens_run() {  # testbed method objects variation factor
  [ "$(sens_pick "$4" "$5" "$1" "$2" "$3")" = NaN ] || return 0
  local show r=$WORK/r.json t0=$SECONDS flag
  show=$("$ZEPHYR" testbed show "$1")
  case $4 in
    host) flag=(--host-ops "$(jq -r --arg f "$5" '.parentHost.mips.value * 1e6 * ($f | tonumber)' <<<"$show")") ;;
    array) flag=(--array-clock "$(jq -r --arg f "$5" '.arrayClockHz * ($f | tonumber)' <<<"$show")") ;;
    latency) flag=(--ethernet-latency "$(jq -r --arg f "$5" '.ethernetLatency.value * ($f | tonumber)' <<<"$show")") ;;
    poll) flag=(--mpi-poll "$(jq -r --arg f "$5" '.mpiPollSeconds.value * ($f | tonumber)' <<<"$show")") ;;
  esac
  "$ZEPHYR" testbed platform --testbed "$1" --children "$K" "${flag[@]}" --out "$WORK/p.xml" --hostfile "$WORK/h"
  rm -f "$r"
  bash "$SIMRUN" --children "$K" --platform "$WORK/p.xml" --hostfile "$WORK/h" --zephyr "$ZEPHYR_SMPI" -- \
    render --no-progress --method "$2" --accel bvh "$(scene "$3")" --frame "$FRAME" --testbed "$1" \
    --report "$r" >"$WORK/log" 2>&1 || { say "failed: $*"; tail -n 3 "$WORK/log" >&2; return 0; }
  row "$1" "$2" bvh "$3" "$K" "$FRAME" 0 "$(( SECONDS - t0 ))" "$r" .testbed | sed "s/^/$4,$5,/" >>"$SENS"
}
SENS_TESTBEDS=$(for t in $TESTBEDS; do case $t in today-*) echo "$t" ;; esac; done)
for t in $SENS_TESTBEDS; do for n in $SENS_COUNTS; do for v in $VARIATIONS; do for f in 0.5 2; do
  for m in dist hetero; do sens_run "$t" "$m" "$n" "$v" "$f"; done
done; done; done; say "$t: sensitivity done (${SECONDS} s)"; done

# ---- Charts ----------------------------------------------------------------------------------
NAMES=(seq simd dist hetero)
TITLES=("sequential" "SIMD/sequential" "distributed $K" "heterogeneous $K")
note() {  # testbed
  case "$1" in
    ufmg1992) echo "modelled 1992 seconds (ufmg1992: SPARCstation 2 parent, SLC children, 10 Mbit/s shared Ethernet, 10 MHz Zephyr); docs/testbed.md" ;;
    today-zephyr) echo "modelled seconds (today-zephyr: a present-day core calibrated, switched 25 GbE, the 10 MHz Zephyr on SCSI-1); docs/present-day.md" ;;
    today-pim) echo "modelled seconds (today-pim: calibrated core, switched 25 GbE, PIM bank at 1.6 GHz on DDR4; array method: 2048 rows); docs/present-day.md" ;;
    *) echo "modelled seconds ($1)" ;;
  esac
}
# pick_method TESTBED METHOD ACCEL OBJECTS [BW]: the sweep's value (the farm's K children; the
# array method's own variant and host tracer).
pick_method() {
  case $2 in
    dist|hetero) pick "$1" "$2" "$3" "$4" "$K" "${5:-0}" $MODEL ;;
    array) pick "$1" "$(array_method "$1")" bvh "$4" 0 0 $MODEL ;;
    *) pick "$1" "$2" "$3" "$4" 0 0 $MODEL ;;
  esac
}
for t in $TESTBEDS; do
  # Modelled time against objects: every method, exhaustive and with the BVH; the array
  # method once (its passes are exhaustive, its few host rays take the BVH).
  csv=$OUT/crossover_$t.csv hdr=objects
  for a in $ACCELS; do for i in "${!NAMES[@]}"; do
    hdr+=",${TITLES[$i]} ($([ "$a" = none ] && echo exhaustive || echo BVH))"
  done; done
  hdr+=",all rays on the array"
  echo "$hdr" >"$csv"
  for n in $COUNTS; do
    line=$n
    for a in $ACCELS; do for m in "${NAMES[@]}"; do line+=",$(pick_method "$t" "$m" "$a" "$n")"; done; done
    echo "$line,$(pick_method "$t" array bvh "$n")" >>"$csv"
  done
  gnuplot -e "in='$csv'; out='${csv%.csv}.png'; ttl='$t: modelled time against objects, exhaustive and with a BVH (${SIZE}x${SIZE})'; \
xl='random spheres'; yl='modelled s'; logx=1; logy=1; note='$(note "$t")'; ncols=10; pairs=4; empty=0" "$GP/lines.gp" ||
    say "gnuplot failed for crossover_$t"

  # Where each method wins with the BVH: objects × Ethernet bandwidth.
  bws=MAP_BW_${t%%-*} bw0=$(own_bw "$t")
  {
    echo "ethernet_bps,objects,winner,seq_s,simd_s,dist_s,hetero_s,array_s"
    for bw in ${!bws}; do for n in $MAP_COUNTS; do
      s=$(pick_method "$t" seq bvh "$n"); d=$(pick_method "$t" simd bvh "$n"); a=$(pick_method "$t" array bvh "$n")
      b=$(map_bw "$bw" "$bw0")
      di=$(pick_method "$t" dist bvh "$n" "$b"); h=$(pick_method "$t" hetero bvh "$n" "$b")
      awk -v bw="$bw" -v n="$n" -v s="$s" -v d="$d" -v di="$di" -v h="$h" -v a="$a" 'BEGIN {
        v[1] = s; v[2] = d; v[3] = di; v[4] = h; v[5] = a; best = 0
        for (i = 1; i <= 5; ++i) if (v[i] != "NaN" && (best == 0 || v[i] + 0 < v[best] + 0)) best = i
        printf "%s,%s,%d,%s,%s,%s,%s,%s\n", bw, n, best, s, d, di, h, a }'
    done; done
  } >"$OUT/wins_bvh_$t.csv"
  gnuplot -e "in='$OUT/wins_bvh_$t.csv'; out='$OUT/wins_bvh_$t.png'; paperbw=${bw0:-1e7}; \
ttl='$t, host tracers with a BVH: the fastest method'; paperlabel='own bandwidth'; \
note='dist/hetero: $K children, frames $FRAME; $(note "$t")'" "$ROOT/tools/testbed/wins.gp" ||
    say "gnuplot failed for wins_bvh_$t"
done

# ---- Summary: who wins at each count, and whether the array pays -------------------------------
# hetero_vs_dist: heterogeneous over distributed with the same children and tracer (< 1: the
# array pays); winner: the fastest of the five.
{
  echo "testbed,accel,objects,winner,winner_s,hetero_vs_dist,simd_vs_seq"
  for t in $TESTBEDS; do for a in $ACCELS; do for n in $COUNTS; do
    s=$(pick_method "$t" seq "$a" "$n"); d=$(pick_method "$t" simd "$a" "$n"); ar=$(pick_method "$t" array "$a" "$n")
    di=$(pick_method "$t" dist "$a" "$n"); h=$(pick_method "$t" hetero "$a" "$n")
    awk -v t="$t" -v acc="$a" -v n="$n" -v s="$s" -v d="$d" -v di="$di" -v h="$h" -v ar="$ar" 'BEGIN {
      split("seq simd dist hetero array", name, " ")
      v[1] = s; v[2] = d; v[3] = di; v[4] = h; v[5] = ar; best = 0
      for (i = 1; i <= 5; ++i) if (v[i] != "NaN" && (best == 0 || v[i] + 0 < v[best] + 0)) best = i
      hd = (h == "NaN" || di == "NaN") ? "NaN" : h / di
      ss = (d == "NaN" || s == "NaN") ? "NaN" : d / s
      printf "%s,%s,%s,%s,%s,%s,%s\n", t, acc, n, best ? name[best] : "none", best ? v[best] : "NaN", hd, ss }'
  done; done; done
} >"$OUT/summary.csv"

# sensitivity.csv: per present-day testbed, count, variation and factor, every method's
# modelled seconds (BVH), the winner, heterogeneous ÷ distributed; factor 1 is the sweep's.
{
  echo "testbed,objects,variation,factor,seq_s,simd_s,dist_s,hetero_s,array_s,winner,hetero_vs_dist"
  for t in $SENS_TESTBEDS; do for n in $SENS_COUNTS; do for v in base $VARIATIONS; do
    for f in $([ "$v" = base ] && echo 1 || echo 0.5 2); do
      local_s=() 
      for m in seq simd array; do
        mm=$m; [ "$m" = array ] && mm=$(array_method "$t")
        a=$(pick "$t" "$mm" bvh "$n" 0 0 9) h=$(pick "$t" "$mm" bvh "$n" 0 0 10)
        local_s+=("$(awk -v a="$a" -v h="$h" -v v="$v" -v f="$f" 'BEGIN {
          if (a == "NaN" || h == "NaN") { print "NaN"; exit }
          if (v == "host") h /= f; else if (v == "array") a /= f
          print a + h }')")
      done
      if [ "$v" = base ]; then
        di=$(pick_method "$t" dist bvh "$n"); h=$(pick_method "$t" hetero bvh "$n")
      else
        di=$(sens_pick "$v" "$f" "$t" dist "$n"); h=$(sens_pick "$v" "$f" "$t" hetero "$n")
      fi
      awk -v t="$t" -v n="$n" -v var="$v" -v f="$f" -v s="${local_s[0]}" -v d="${local_s[1]}" \
          -v ar="${local_s[2]}" -v di="$di" -v h="$h" 'BEGIN {
        split("seq simd dist hetero array", name, " ")
        x[1] = s; x[2] = d; x[3] = di; x[4] = h; x[5] = ar; best = 0
        for (i = 1; i <= 5; ++i) if (x[i] != "NaN" && (best == 0 || x[i] + 0 < x[best] + 0)) best = i
        hd = (h == "NaN" || di == "NaN") ? "NaN" : h / di
        printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", t, n, var, f, s, d, di, h, ar, best ? name[best] : "none", hd }'
    done
  done; done; done
} >"$OUT/sensitivity.csv"

say "wrote $OUT (runs.csv has every render)"
exit 0
}
