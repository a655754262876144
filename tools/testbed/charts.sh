#!/usr/bin/env bash
# tools/testbed/charts.sh — `make charts TESTBED=ufmg1992` (docs/testbed.md): the paper's
# Figs 5–12 in modelled 1992 seconds, where each method wins, and past the paper (8 → 256
# simulated children). seq/simd come from `zephyr render --testbed`; dist/hetero from
# build/bin/zephyr-smpi under smpirun (tools/testbed/simrun.sh). Every figure is read from
# the JSON reports. Output: docs/results/testbed-NAME/ (CSV + PNG).
#
# Environment: TESTBED (default ufmg1992), QUICK=1 (64×64, few points), OUT=dir,
#   ZEPHYR / ZEPHYR_SMPI (default build/bin/zephyr, build/bin/zephyr-smpi),
#   REUSE=1 (keep OUT/runs.csv and render only the points it lacks: the model is
#   deterministic, so a point once rendered does not change unless the code does).
set -euo pipefail
# The whole script is one block, read before it runs: editing this file during a long sweep
# does not change the running one.
{

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
abspath() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
TESTBED=${TESTBED:-ufmg1992}
ZEPHYR=$(abspath "${ZEPHYR:-$ROOT/build/bin/zephyr}")
ZEPHYR_SMPI=$(abspath "${ZEPHYR_SMPI:-$ROOT/build/bin/zephyr-smpi}")
OUT=$(abspath "${OUT:-$ROOT/docs/results/testbed-$TESTBED}")
GP=$ROOT/tools/charts
SIMRUN=$ROOT/tools/testbed/simrun.sh

if [ -n "${QUICK:-}" ] && [ "${QUICK}" != 0 ]; then
  SIZE=64 COUNTS="8 32" CHILDREN="2" FRAMES="32 16" REF_COUNT=32 PAST="2 4" PAST_SERIES="32:32 32:16 8:16"
  MAP_BW="1e6 1e7" MAP_COUNTS="8 32"
else
  SIZE=384 COUNTS="8 16 32 64 128 256" CHILDREN="2 4 8" FRAMES="128 64 32" REF_COUNT=64
  PAST="8 16 32 64 128 256" PAST_SERIES="64:128 64:64 64:32 8:16"
  MAP_BW="1e5 1e6 1e7 1e8" MAP_COUNTS="8 32 128"
fi
SEED=${SEED:-1} NAME="testbed charts"
. "$ROOT/tools/testbed/sweep.sh"
# Past the paper: series OBJECTS:FRAME over the child counts PAST (and CHILDREN).
PAST_COUNTS=$(for s in $PAST_SERIES; do echo "${s%%:*}"; done | sort -n | uniq | tr '\n' ' ')
say "$TESTBED: ${SIZE}x${SIZE}, objects {$COUNTS}, children {$CHILDREN}, frames {$FRAMES}, past {$PAST} x {$PAST_SERIES}"

make_scenes $COUNTS $REF_COUNT $MAP_COUNTS $PAST_COUNTS

RUNS=$OUT/runs.csv
HEADER="method,objects,children,frame,ethernet_bps,model_s,bytes,pixels,frames_sent,frames_skipped,child_busy_s,ethernet_busy,parent_busy,wall_s"
if [ "${REUSE:-0}" = 0 ] || [ ! -f "$RUNS" ] || [ "$(head -1 "$RUNS")" != "$HEADER" ]; then
  echo "$HEADER" >"$RUNS"
fi
# One row from a report: model_s is .testbed.modelledSeconds; bytes both ways with envelopes;
# child_busy_s the mean simulated busy seconds of the children; ethernet_busy the simulated
# Ethernet's busy fraction (bytes / bandwidth / modelled time, SimGrid's link_load);
# parent_busy the parent's array pass + charged host work over the modelled time.
row() {  # method objects children frame bw report wall
  jq -r --arg m "$1" --arg n "$2" --arg k "$3" --arg f "$4" --arg bw "$5" --arg w "$6" '
    def tot(x): (x.total.payloadBytes + x.total.envelopeBytes);
    [$m, $n, $k, $f, $bw, .testbed.modelledSeconds,
     (if .distributed then tot(.distributed.traffic.parentToChildren) + tot(.distributed.traffic.childrenToParent) else 0 end),
     (if .distributed then ([.distributed.perChild[].pixels] | add) else .pixels end),
     (if .distributed then .distributed.frames.sent else 0 end),
     (if .distributed then .distributed.frames.skipped else 0 end),
     (if .distributed then ([.testbed.children[] | .busySeconds // 0] | add / length) else 0 end),
     (if .distributed then ([.testbed.links[] | select(.link == "ethernet") | .busyFraction] | add // 0) else 0 end),
     (if .distributed then ((.testbed.parent.arrayPassSeconds + .testbed.parent.hostWorkSeconds) / .testbed.modelledSeconds) else 0 end),
     $w] | @csv' "$7" | tr -d '"' >>"$RUNS"
}
local_run() {  # method objects
  local r=$WORK/r.json t0=$SECONDS
  [ "$(pick "$1" "$2" 0 0 0 "$MODEL")" = NaN ] || return 0  # REUSE=1: already rendered
  "$ZEPHYR" render --no-progress --method "$1" "$(scene "$2")" --testbed "$TESTBED" --report "$r" >/dev/null 2>&1 ||
    { say "failed: $1 $2"; return 0; }
  row "$1" "$2" 0 0 0 "$(( SECONDS - t0 ))" "$r"
}
sim_run() {  # method objects children frame [ethernet_bps]
  local r=$WORK/r.json t0=$SECONDS plat=() bw=${5:-0}
  [ "$(pick "$1" "$2" "$3" "$4" "$bw" "$MODEL")" = NaN ] || return 0  # already rendered
  if [ "$bw" != 0 ]; then
    "$ZEPHYR" testbed platform --testbed "$TESTBED" --children "$3" --ethernet-bps "$bw" --out "$WORK/p.xml" --hostfile "$WORK/h"
    plat=(--platform "$WORK/p.xml" --hostfile "$WORK/h")
  fi
  rm -f "$r"
  bash "$SIMRUN" --children "$3" --testbed "$TESTBED" "${plat[@]}" --zephyr "$ZEPHYR_SMPI" -- render --no-progress \
    --method "$1" "$(scene "$2")" --frame "$4" --testbed "$TESTBED" --report "$r" >"$WORK/log" 2>&1 ||
    { say "failed: $*"; tail -n 3 "$WORK/log" >&2; return 0; }
  row "$1" "$2" "$3" "$4" "$bw" "$(( SECONDS - t0 ))" "$r"
}

# ---- Tables: x, then one column per series (NaN where missing) -----------------------------
# pick METHOD OBJECTS CHILDREN FRAME BW COLUMN: the value of the first matching row.
pick() {
  awk -F, -v m="$1" -v n="$2" -v k="$3" -v f="$4" -v bw="$5" -v c="$6" \
    'NR > 1 && $1 == m && $2 == n && $3 == k && $4 == f && $5 == bw { print $c; found = 1; exit }
     END { if (!found) print "NaN" }' "$RUNS"
}
col() { awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == name) print i }' "$RUNS"; }
MODEL=$(col model_s) BYTES=$(col bytes) PIXELS=$(col pixels) BUSY=$(col child_busy_s)
ETH=$(col ethernet_busy) PARENT=$(col parent_busy)

LAST_FRAME=${FRAMES##* }
for n in $COUNTS; do local_run seq "$n"; local_run simd "$n"; local_run array "$n"; done
for n in $COUNTS; do for k in $CHILDREN; do for f in $FRAMES; do
  sim_run dist "$n" "$k" "$f"; sim_run hetero "$n" "$k" "$f"
done; done; say "objects $n done (${SECONDS} s)"; done
MAXK=${CHILDREN##* }
ALLK=$(printf '%s\n' $CHILDREN $PAST | sort -n | uniq | tr '\n' ' ')
for k in $ALLK; do for s in $PAST_SERIES; do for m in dist hetero; do
  sim_run "$m" "${s%%:*}" "$k" "${s##*:}"
done; done; say "past the paper: $k children done (${SECONDS} s)"; done
for bw in $MAP_BW; do for n in $MAP_COUNTS; do
  sim_run dist "$n" "$MAXK" "$LAST_FRAME" "$bw"; sim_run hetero "$n" "$MAXK" "$LAST_FRAME" "$bw"
done; done

table() {  # out header x-values row-command...
  local out=$1 header=$2 xs=$3; shift 3
  echo "$header" >"$out"
  for x in $xs; do
    local line=$x
    for spec in "$@"; do line+=",$(eval "${spec//@/$x}")"; done
    echo "$line" >>"$out"
  done
}
chart() {  # name title xlabel ylabel logx logy note
  local ncols; ncols=$(head -1 "$OUT/$1.csv" | awk -F, '{print NF}')
  gnuplot -e "in='$OUT/$1.csv'; out='$OUT/$1.png'; ttl='$2'; xl='$3'; yl='$4'; logx=$5; logy=$6; \
note='$7'; ncols=$ncols; empty=0" "$GP/lines.gp" || say "gnuplot failed for $1"
}
NOTE="modelled 1992 seconds ($TESTBED: SPARCstation 2 parent, SLC children, 10 Mbit/s shared Ethernet, 10 MHz Zephyr); docs/testbed.md"

table "$OUT/fig05_seq_vs_simd.csv" "objects,sequential,SIMD/sequential" "$COUNTS" \
  "pick seq @ 0 0 0 $MODEL" "pick simd @ 0 0 0 $MODEL"
chart fig05_seq_vs_simd "Fig 5: sequential vs SIMD/sequential (${SIZE}x${SIZE})" objects "modelled s" 1 1 "$NOTE"

specs=("pick seq @ 0 0 0 $MODEL") hdr="objects,sequential"
for k in $CHILDREN; do specs+=("pick dist @ $k $LAST_FRAME 0 $MODEL"); hdr+=",distributed $k children"; done
table "$OUT/fig06_seq_vs_dist.csv" "$hdr" "$COUNTS" "${specs[@]}"
chart fig06_seq_vs_dist "Fig 6: sequential vs distributed (frames $LAST_FRAME)" objects "modelled s" 1 1 "$NOTE"

fig=7
for k in $CHILDREN; do
  specs=() hdr="objects"
  for f in $FRAMES; do
    specs+=("pick dist @ $k $f 0 $MODEL" "pick hetero @ $k $f 0 $MODEL"); hdr+=",distributed $f,heterogeneous $f"
  done
  name=$(printf 'fig%02d_hetero_vs_dist_%schildren' "$fig" "$k")
  table "$OUT/$name.csv" "$hdr" "$COUNTS" "${specs[@]}"
  chart "$name" "Fig $fig: heterogeneous vs distributed, $k children" objects "modelled s" 1 1 "$NOTE"
  fig=$((fig + 1))
done

table "$OUT/fig10_data_flow.csv" "frame,distributed,heterogeneous" "$FRAMES" \
  "pick dist $REF_COUNT $MAXK @ 0 $BYTES" "pick hetero $REF_COUNT $MAXK @ 0 $BYTES"
chart fig10_data_flow "Fig 10: bytes parent<->children ($REF_COUNT objects, $MAXK children)" "frame size" bytes 1 0 "$NOTE"
table "$OUT/fig11_pixels.csv" "frame,distributed,heterogeneous" "$FRAMES" \
  "pick dist $REF_COUNT $MAXK @ 0 $PIXELS" "pick hetero $REF_COUNT $MAXK @ 0 $PIXELS"
chart fig11_pixels "Fig 11: pixels processed by the children" "frame size" pixels 1 0 "$NOTE"

table "$OUT/fig12_all_methods.csv" "objects,sequential,SIMD/sequential,distributed $MAXK,heterogeneous $MAXK,all rays on the array" "$COUNTS" \
  "pick seq @ 0 0 0 $MODEL" "pick simd @ 0 0 0 $MODEL" \
  "pick dist @ $MAXK $LAST_FRAME 0 $MODEL" "pick hetero @ $MAXK $LAST_FRAME 0 $MODEL" \
  "pick array @ 0 0 0 $MODEL"
chart fig12_all_methods "Fig 12: all methods ($MAXK children, frames $LAST_FRAME)" objects "modelled s" 1 1 "$NOTE"

# ---- All rays on the array: SIMD utilisation per bounce, with and without compaction -------
# (docs/wavefront.md, "Compaction"): live rays ÷ the slots the controller ran, and the cycles.
for c in none local mesh; do
  "$ZEPHYR" render --no-progress --method array --compact "$c" "$(scene "$REF_COUNT")" \
    --testbed "$TESTBED" --report "$WORK/compact-$c.json" >/dev/null 2>&1 || say "failed: array --compact $c"
done
{
  echo "bounce,utilisation none,utilisation local,utilisation mesh,layers none,layers local,layers mesh,cycles none,cycles local,cycles mesh"
  paste -d, <(jq -r '.wavefront.bounces[] | [.bounce, .utilisation, .layers, .cycles] | @csv' "$WORK/compact-none.json") \
            <(jq -r '.wavefront.bounces[] | [.utilisation, .layers, .cycles] | @csv' "$WORK/compact-local.json") \
            <(jq -r '.wavefront.bounces[] | [.utilisation, .layers, .cycles] | @csv' "$WORK/compact-mesh.json") |
    awk -F, '{ printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", $1, $2, $5, $8, $3, $6, $9, $4, $7, $10 }'
} >"$OUT/array_utilisation.csv"
cut -d, -f1-4 "$OUT/array_utilisation.csv" >"$WORK/util.csv"
gnuplot -e "in='$WORK/util.csv'; out='$OUT/array_utilisation.png'; ttl='All rays on the array: SIMD utilisation per bounce ($REF_COUNT spheres)'; \
xl='bounce (1 = the primary hits)'; yl='live rays / slots run'; logx=0; logy=0; note='$NOTE'; ncols=4; empty=0" "$GP/lines.gp" ||
  say "gnuplot failed for array_utilisation"

# ---- Past the paper: children busy fraction (efficiency) and the Ethernet's load ------------
# past NAME TITLE YLABEL LOGY SPEC: one column per method and series (objects:frame) over
# every child count, SPEC a command with @ for the child count, %M the method, %N the objects
# and %F the frame.
past() {
  local name=$1 title=$2 yl=$3 logy=$4 spec=$5 specs=() hdr="children" s m one
  for s in $PAST_SERIES; do
    for m in dist hetero; do
      one=${spec//%M/$m}; one=${one//%N/${s%%:*}}
      specs+=("${one//%F/${s##*:}}"); hdr+=",$m ${s%%:*} spheres ${s##*:}"
    done
  done
  table "$OUT/$name.csv" "$hdr" "$ALLK" "${specs[@]}"
  chart "$name" "$title" children "$yl" 1 "$logy" "$NOTE"
}
ratio() { awk -v b="$1" -v t="$2" 'BEGIN { if (b == "NaN" || t == "NaN" || t == 0) print "NaN"; else print b / t }'; }
past past_efficiency "Past the paper: children busy / modelled time (series: method, spheres, frame)" efficiency 0 \
  "ratio \$(pick %M %N @ %F 0 $BUSY) \$(pick %M %N @ %F 0 $MODEL)"
past past_ethernet "Past the paper: busy fraction of the shared Ethernet (SimGrid link_load)" "busy fraction" 0 \
  "pick %M %N @ %F 0 $ETH"
past past_parent "Past the paper: busy fraction of the parent (array pass + own work)" "busy fraction" 0 \
  "pick %M %N @ %F 0 $PARENT"
past past_time "Past the paper: modelled time vs children (series: method, spheres, frame)" "modelled s" 1 \
  "pick %M %N @ %F 0 $MODEL"

# ---- Where each method wins: Ethernet bandwidth x objects, $MAXK children ----------------------
{
  echo "ethernet_bps,objects,winner,seq_s,simd_s,dist_s,hetero_s,array_s"
  for bw in $MAP_BW; do for n in $MAP_COUNTS; do
    s=$(pick seq "$n" 0 0 0 "$MODEL"); d=$(pick simd "$n" 0 0 0 "$MODEL"); a=$(pick array "$n" 0 0 0 "$MODEL")
    if [ "$s" = NaN ] || [ "$a" = NaN ]; then
      local_run seq "$n"; local_run simd "$n"; local_run array "$n"
      s=$(pick seq "$n" 0 0 0 "$MODEL"); d=$(pick simd "$n" 0 0 0 "$MODEL"); a=$(pick array "$n" 0 0 0 "$MODEL")
    fi
    di=$(pick dist "$n" "$MAXK" "$LAST_FRAME" "$bw" "$MODEL"); h=$(pick hetero "$n" "$MAXK" "$LAST_FRAME" "$bw" "$MODEL")
    awk -v bw="$bw" -v n="$n" -v s="$s" -v d="$d" -v di="$di" -v h="$h" -v a="$a" 'BEGIN {
      v[1] = s; v[2] = d; v[3] = di; v[4] = h; v[5] = a; best = 0
      for (i = 1; i <= 5; ++i) if (v[i] != "NaN" && (best == 0 || v[i] + 0 < v[best] + 0)) best = i
      printf "%s,%s,%d,%s,%s,%s,%s,%s\n", bw, n, best, s, d, di, h, a }'
  done; done
} >"$OUT/where_each_wins.csv"
gnuplot -e "in='$OUT/where_each_wins.csv'; out='$OUT/where_each_wins.png'; paperbw=10e6; note='dist/hetero: $MAXK children, frames $LAST_FRAME; $NOTE'" \
  "$ROOT/tools/testbed/wins.gp" || say "gnuplot failed for where_each_wins"

say "wrote $OUT (runs.csv has every render)"
exit 0
}
