#!/usr/bin/env bash
# tools/charts.sh — `make charts` (issue 7): the paper's §6 experiments, speed against
# accuracy, and where the sphere test fails, as CSV data and PNG charts under docs/results/.
#
# Written in bash + jq + awk + gnuplot (tools/setup.sh installs jq and gnuplot-nox): every
# figure is read from the JSON reports `zephyr render --report` writes, never from printed
# text; the stability study comes from `zephyr stability` (hosts/stability_command.cpp) as CSV.
#
# Environment:
#   QUICK=1        tiny sweeps (64×64 images, 2 object counts) — `make test` runs this
#   ZEPHYR=path    the zephyr program (default build/bin/zephyr)
#   OUT=dir        where the CSV/PNG go (default docs/results)
#   MPIRUN=cmd     the MPI launcher (default mpirun)
# Methods that the zephyr program does not list in `render --help` yet are skipped, with a
# note printed here and on the chart, so the chain works while methods land.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
abspath() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
ZEPHYR=$(abspath "${ZEPHYR:-$ROOT/build/bin/zephyr}")
OUT=$(abspath "${OUT:-$ROOT/docs/results}")
GP=$ROOT/tools/charts
MPIRUN=${MPIRUN:-mpirun}

if [ -n "${QUICK:-}" ] && [ "${QUICK}" != 0 ]; then
  MODE=quick SIZE=64 COUNTS="8 32" CHILDREN="2" FRAMES="32 16" REF_COUNT=32 FRAC="4 8 16"
  STAB_DIST=(--rays 32 --max-log2 14 --steps 1) STAB_OVER=(--max-int-bits 10)
else
  MODE=full SIZE=384 COUNTS="8 16 32 64 128 256" CHILDREN="2 4 8" FRAMES="128 64 32"
  REF_COUNT=64 FRAC="4 6 8 10 12 14 16 20 24"
  STAB_DIST=(--rays 256 --max-log2 24 --steps 2) STAB_OVER=(--max-int-bits 32)
fi
SEED=${SEED:-1}

for tool in jq gnuplot awk; do
  command -v "$tool" >/dev/null || { echo "charts: $tool not found (run tools/setup.sh)" >&2; exit 1; }
done
[ -x "$ZEPHYR" ] || { echo "charts: $ZEPHYR not built (make build)" >&2; exit 1; }

mkdir -p "$OUT"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/zephyr-charts.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
say() { echo "charts: $*" >&2; }

# ---- What this machine and this build can do ----------------------------------------
CPU=$(lscpu 2>/dev/null | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2; exit}')
CORES=$(nproc)
METHODS=$("$ZEPHYR" render --help | sed -n 's/.*--method.*Method: *//p')
has_method() { [[ ",$(tr -d ' ' <<<"$METHODS")," == *",$1,"* ]]; }
has_command() { "$ZEPHYR" "$1" --help >/dev/null 2>&1; }
MPI_FLAGS=(--oversubscribe)
[ "$(id -u)" = 0 ] && MPI_FLAGS+=(--allow-run-as-root)
has_mpi() { command -v "$MPIRUN" >/dev/null; }
SKIPPED=""
skip() { say "skipped: $*"; SKIPPED+="$*; "; }
for m in seq simd dist hetero; do has_method "$m" || skip "$m (not in zephyr render --method yet)"; done
for m in dist hetero; do
  if has_method "$m" && ! has_mpi; then skip "$m ($MPIRUN not found)"; fi
done
say "$MODE run: ${SIZE}x${SIZE}, objects {$COUNTS}, children {$CHILDREN}, frames {$FRAMES}; methods: $METHODS; $CPU, $CORES cores"

# ---- Scenes ------------------------------------------------------------------------------
scene() { echo "$WORK/spheres-$1.nff"; }
for n in $COUNTS $REF_COUNT; do
  [ -f "$(scene "$n")" ] || "$ZEPHYR" gen spheres --count "$n" --seed "$SEED" --size "${SIZE}x${SIZE}" --out "$(scene "$n")"
done

# ---- Runs: every render appends one row of runs.csv from its JSON report ---------------
RUNS=$OUT/runs.csv
echo "method,objects,children,frame,host_s,model_s,bytes_p2c,bytes_c2p,pixels,frames_total,frames_sent,frames_skipped" >"$RUNS"

# The figures the reports carry, wherever in the tree the method put them:
#   host_s   .phases.render (wall seconds of the whole render, on this host)
#   model_s  the first number whose key names modelled seconds (the SIMD machine at its clock)
#   bytes    traffic.{parentToChildren,childrenToParent}.total payload + envelope bytes
#   pixels   sum of perChild[].pixels; frames from the object with skippedIds
JQ_ROW='
  def first_obj(f): first(.. | objects | select(f)) // null;
  def modelled: first(paths(numbers) as $p
      | select(($p[-1] | tostring) | test("modell?ed.*(sec|time)|^modell?ed_?s$"; "i"))
      | getpath($p)) // null;
  def bytes(d): (first_obj(has("parentToChildren")) | if . == null then null
      else .[d].total | (.payloadBytes + .envelopeBytes) end);
  (first_obj(has("perChild"))) as $farm | (first_obj(has("skippedIds"))) as $frames |
  [ .phases.render, modelled, bytes("parentToChildren"), bytes("childrenToParent"),
    (if $farm == null then null else ([$farm.perChild[].pixels] | add) end),
    $frames.total?, $frames.sent?, $frames.skipped? ]
  | map(if . == null then "NaN" else tostring end) | join(",")'

# run METHOD OBJECTS CHILDREN FRAME [extra render flags...] — one render, one row.
run() {
  local method=$1 n=$2 k=$3 f=$4; shift 4
  local json=$WORK/$method-$n-$k-$f.json
  local cmd=("$ZEPHYR" render --method "$method" --scene "$(scene "$n")" --report "$json" --no-progress "$@")
  case $method in
    dist|hetero) cmd=("$MPIRUN" "${MPI_FLAGS[@]}" -np $((k + 1)) "${cmd[@]}" --frame "$f") ;;
  esac
  if ! "${cmd[@]}" >"$WORK/last.log" 2>&1; then
    say "failed: ${cmd[*]}"; tail -n 5 "$WORK/last.log" >&2
    skip "$method n=$n k=$k f=$f (run failed)"
    return 0
  fi
  echo "$method,$n,$k,$f,$(jq -r "$JQ_ROW" "$json")" >>"$RUNS"
}

# value METHOD OBJECTS CHILDREN FRAME COLUMN — a figure from runs.csv, NaN if not run.
value() {
  awk -F, -v m="$1" -v n="$2" -v k="$3" -v f="$4" -v c="$5" '
    NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
    $1 == m && $2 == n && $3 == k && $4 == f { v = $col[c] }
    END { print (v == "" ? "NaN" : v) }' "$RUNS"
}

for n in $COUNTS; do
  has_method seq && run seq "$n" 0 0
  has_method simd && run simd "$n" 0 0
  if has_mpi; then
    for k in $CHILDREN; do
      for f in $FRAMES; do
        has_method dist && run dist "$n" "$k" "$f"
        has_method hetero && run hetero "$n" "$k" "$f"
      done
    done
  fi
  say "objects $n done"
done

# ---- Charts ------------------------------------------------------------------------------
# chart NAME TITLE XLABEL YLABEL LOGX LOGY NOTE [NOTE2] — draws $OUT/NAME.png from $OUT/NAME.csv.
chart() {
  local name=$1 csv=$OUT/$1.csv empty=1
  awk -F, 'NR > 1 { for (i = 2; i <= NF; ++i) if ($i != "NaN") found = 1 } END { exit !found }' "$csv" && empty=0
  gnuplot -e "in='$csv'; out='$OUT/$name.png'; ttl='$2'; xl='$3'; yl='$4'; logx=$5; logy=$6; \
note='$7'; note2='${8:-}'; ncols=$(head -1 "$csv" | awk -F, '{print NF}'); empty=$empty" "$GP/lines.gp" \
    2> >(grep -v 'Skipping data file with no valid points' >&2)
  say "wrote $OUT/$name.png"
}
note_for() {  # the skip notes that concern the given methods, plus the machine
  local n="" m
  for m in "$@"; do has_method "$m" || n+="$m: not available yet (skipped). "; done
  echo "${n}${SIZE}x${SIZE} random spheres, seed $SEED; $CPU, $CORES cores; $(date +%Y-%m-%d)"
}
OVERSUB="children beyond the $CORES cores are oversubscribed (share cores with the parent)"
SIMD_LABELS="SIMD model = modelled machine time at the profile clock; SIMD host = emulator wall time on this host"
max_k=${CHILDREN##* }
frame_for_k() { echo "${FRAMES##* }"; }  # the smallest frame: the paper's best case

# Fig 5: sequential vs SIMD/sequential.
{ echo "objects,sequential,SIMD/seq (host time),SIMD/seq (modelled machine)"
  for n in $COUNTS; do
    echo "$n,$(value seq "$n" 0 0 host_s),$(value simd "$n" 0 0 host_s),$(value simd "$n" 0 0 model_s)"
  done; } >"$OUT/fig05_seq_vs_simd.csv"
chart fig05_seq_vs_simd "Fig 5: sequential vs SIMD/sequential" "objects" "seconds" 1 1 \
  "$(note_for seq simd)" "$SIMD_LABELS"

# Fig 6: sequential vs distributed with each number of children (smallest frame).
f=$(frame_for_k)
{ printf "objects,sequential"; for k in $CHILDREN; do printf ",distributed %s children" "$k"; done; echo
  for n in $COUNTS; do
    printf "%s,%s" "$n" "$(value seq "$n" 0 0 host_s)"
    for k in $CHILDREN; do printf ",%s" "$(value dist "$n" "$k" "$f" host_s)"; done; echo
  done; } >"$OUT/fig06_seq_vs_dist.csv"
chart fig06_seq_vs_dist "Fig 6: sequential vs distributed (frames ${f}x${f})" "objects" "seconds" 1 1 \
  "$(note_for seq dist)" "$OVERSUB"

# Figs 7-9: heterogeneous vs distributed for each frame size, one chart per child count.
fig=7
for k in $CHILDREN; do
  name=$(printf "fig%02d_hetero_vs_dist_%dchildren" "$fig" "$k")
  { printf "objects"; for f in $FRAMES; do printf ",distributed %sx%s,heterogeneous %sx%s" "$f" "$f" "$f" "$f"; done; echo
    for n in $COUNTS; do
      printf "%s" "$n"
      for f in $FRAMES; do printf ",%s,%s" "$(value dist "$n" "$k" "$f" host_s)" "$(value hetero "$n" "$k" "$f" host_s)"; done
      echo
    done; } >"$OUT/$name.csv"
  chart "$name" "Fig $fig: heterogeneous vs distributed, $k children" "objects" "seconds" 1 1 \
    "$(note_for dist hetero)" "$([ "$k" -ge "$CORES" ] && echo "$OVERSUB")"
  fig=$((fig + 1))
done

# Figs 10 and 11: data flow and pixels processed against frame size (REF_COUNT objects,
# the most children).
for what in bytes pixels; do
  if [ $what = bytes ]; then name=fig10_data_flow; ttl="Fig 10: data flow parent<->children"; yl="bytes (both ways)"
  else name=fig11_pixels; ttl="Fig 11: pixels processed by the children"; yl="pixels"; fi
  { echo "frame size,distributed,heterogeneous"
    for f in $FRAMES; do
      row="$f"
      for m in dist hetero; do
        if [ $what = bytes ]; then
          a=$(value "$m" "$REF_COUNT" "$max_k" "$f" bytes_p2c) b=$(value "$m" "$REF_COUNT" "$max_k" "$f" bytes_c2p)
          row+=",$(awk -v a="$a" -v b="$b" 'BEGIN { print (a == "NaN" || b == "NaN") ? "NaN" : a + b }')"
        else
          row+=",$(value "$m" "$REF_COUNT" "$max_k" "$f" pixels)"
        fi
      done
      echo "$row"
    done; } >"$OUT/$name.csv"
  chart "$name" "$ttl ($REF_COUNT objects, $max_k children)" "frame size (pixels a side)" "$yl" 1 0 \
    "$(note_for dist hetero)"
done

# Fig 12: all four methods (the most children, the smallest frame).
{ echo "objects,sequential,SIMD/seq (host time),SIMD/seq (modelled machine),distributed $max_k children,heterogeneous $max_k children"
  for n in $COUNTS; do
    echo "$n,$(value seq "$n" 0 0 host_s),$(value simd "$n" 0 0 host_s),$(value simd "$n" 0 0 model_s),$(value dist "$n" "$max_k" "$f" host_s),$(value hetero "$n" "$max_k" "$f" host_s)"
  done; } >"$OUT/fig12_all_methods.csv"
chart fig12_all_methods "Fig 12: the four methods (frames ${f}x${f})" "objects" "seconds" 1 1 \
  "$(note_for seq simd dist hetero)" "$SIMD_LABELS; $OVERSUB"

# ---- Stability: where the sphere test fails ----------------------------------------------
"$ZEPHYR" stability distance "${STAB_DIST[@]}" --out "$OUT/stability_distance.csv"
STAB_NOTE="radius-1 sphere at distance D, fan of rays from the centre out to 1.25 r; exact reference: 128-bit floats on the same rounded inputs; fixed: floor, saturate"
gnuplot -e "in='$OUT/stability_distance.csv'; out='$OUT/stability_wrong_hits.png'; ycol=5; logy=0; \
yl='% of rays with the wrong hit/miss'; ttl='Where methods fail: wrong hit/miss against distance'; \
note='$STAB_NOTE'" "$GP/stability.gp"
gnuplot -e "in='$OUT/stability_distance.csv'; out='$OUT/stability_t_error.png'; ycol=8; logy=1; \
yl='max relative error in t (hits)'; ttl='Where methods fail: error in t against distance'; \
note='$STAB_NOTE; 0 drawn at 1e-17'" "$GP/stability.gp"
say "wrote $OUT/stability_wrong_hits.png $OUT/stability_t_error.png"
"$ZEPHYR" stability overflow "${STAB_OVER[@]}" --out "$OUT/stability_overflow.csv"
gnuplot -e "in='$OUT/stability_overflow.csv'; out='$OUT/stability_overflow.png'; \
note='fraction bits F = 16; a quarter-octave scan of D from 2 r; the fan of 16 rays as above'" "$GP/overflow.gp"
say "wrote $OUT/stability_overflow.png"

# ---- Speed against accuracy ---------------------------------------------------------------
source "$ROOT/tools/charts/accuracy.sh"

{ echo "mode,$MODE"; echo "size,$SIZE"; echo "objects,$(tr ' ' ';' <<<"$COUNTS")"
  echo "children,$(tr ' ' ';' <<<"$CHILDREN")"; echo "frames,$(tr ' ' ';' <<<"$FRAMES")"
  echo "seed,$SEED"; echo "cpu,$CPU"; echo "cores,$CORES"; echo "date,$(date -Iseconds)"
  echo "methods,$(tr -d ' ' <<<"$METHODS" | tr ',' ';')"; echo "skipped,${SKIPPED//,/;}"
} >"$OUT/run_info.csv"
say "done: $OUT (run_info.csv says what ran)"
