#!/usr/bin/env bash
# tools/charts.sh — `make charts`: the paper's §6 experiments, speed against
# accuracy, and where the sphere test fails, as CSV data and PNG charts under docs/results/.
#
# Written in bash + jq + awk + gnuplot (tools/setup.sh installs jq and gnuplot-nox): every
# figure is read from the JSON reports `zephyr render --report` writes, never from printed
# text; the stability study comes from `zephyr stability` (hosts/cmd/stability.cpp) as CSV.
#
# Environment:
#   QUICK=1        tiny sweeps (64×64 images, 2 object counts, 1 repetition) — `make test` runs this
#   REPS=n         repetitions of each timed render in the full run (default 5; medians charted)
#   ACC_SAMPLE=n   pixels `zephyr accuracy` samples for the first-object and t errors
#   ZEPHYR=path    the zephyr program (default build/bin/zephyr)
#   OUT=dir        where the CSV/PNG go (default docs/results)
#   MPIRUN=cmd     the MPI launcher (default mpirun)
#   SCENES=dir     SPD scenes (lattice_s1.nff) for the recompute-share chart; optional
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
  REPS=1 ACC_SAMPLE=1024
  STAB_DIST=(--rays 32 --max-log2 14 --steps 1) STAB_OVER=(--max-int-bits 10)
else
  MODE=full SIZE=384 COUNTS="8 16 32 64 128 256" CHILDREN="2 4 8" FRAMES="128 64 32"
  REF_COUNT=64 FRAC="4 6 8 10 12 14 16 20 24"
  REPS=${REPS:-5} ACC_SAMPLE=${ACC_SAMPLE:-16384}
  STAB_DIST=(--rays 256 --max-log2 24 --steps 2) STAB_OVER=(--max-int-bits 32)
fi
SEED=${SEED:-1}
RUN_TIMEOUT=${RUN_TIMEOUT:-300}  # seconds; a stuck MPI job is killed and its point skipped

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
echo "method,objects,children,frame,rep,host_s,time_s,model_s,simd_host_s,shade_s,bytes_p2c,bytes_c2p,pixels,frames_total,frames_sent,frames_skipped" >"$RUNS"

# The figures, by the keys the reports carry (hosts/methods/render.cpp, simd.cpp, hosts/farm/parent.cpp):
#   host_s       .phases.render: wall seconds of the render phase on this host (dist/hetero:
#                MPI starts before it, so start-up is not included; the children's stop is)
#   time_s       the method's time as the paper measures it: seq/simd the render phase;
#                dist/hetero .distributed.time.parentPassSeconds (hetero's SIMD pass on the
#                parent) + .distributionSeconds (first setup sent -> last frame back)
#   model_s      .simd.modelledSeconds: the SIMD machine's cycles at the profile's clock
#   simd_host_s  .simd.hostSeconds: the emulator's wall time for those cycles
#   shade_s      .phases.hostShading: simd's shading of the matrix on the host
#   bytes        .distributed.traffic.{parentToChildren,childrenToParent}.total payload + envelope
#   pixels       sum of .distributed.perChild[].pixels; frames from .distributed.frames
JQ_ROW='
  def bytes(d): .distributed.traffic[d].total | if . == null then null
      else .payloadBytes + .envelopeBytes end;
  .distributed as $d |
  [ .phases.render,
    (if $d == null then .phases.render
     else ($d.time.parentPassSeconds // 0) + $d.time.distributionSeconds end),
    .simd.modelledSeconds, .simd.hostSeconds, .phases.hostShading,
    bytes("parentToChildren"), bytes("childrenToParent"),
    (if $d == null then null else ([$d.perChild[].pixels] | add) end),
    $d.frames.total?, $d.frames.sent?, $d.frames.skipped? ]
  | map(if . == null then "NaN" else tostring end) | join(",")'

# run METHOD OBJECTS CHILDREN FRAME REP [extra render flags...] — one render, one row.
run() {
  local method=$1 n=$2 k=$3 f=$4 rep=$5; shift 5
  local json=$WORK/$method-$n-$k-$f-$rep.json
  local cmd=("$ZEPHYR" render --method "$method" --scene "$(scene "$n")" --report "$json" --no-progress "$@")
  case $method in
    dist|hetero) cmd=(timeout -k 5 "$RUN_TIMEOUT" "$MPIRUN" "${MPI_FLAGS[@]}" -np $((k + 1)) "${cmd[@]}" --frame "$f") ;;
    *) cmd=(timeout -k 5 "$RUN_TIMEOUT" "${cmd[@]}") ;;
  esac
  if ! "${cmd[@]}" >"$WORK/last.log" 2>&1; then
    say "failed: ${cmd[*]}"; tail -n 5 "$WORK/last.log" >&2
    skip "$method n=$n k=$k f=$f (run failed)"
    return 0
  fi
  echo "$method,$n,$k,$f,$rep,$(jq -r "$JQ_ROW" "$json")" >>"$RUNS"
}

# value METHOD OBJECTS CHILDREN FRAME COLUMN — the median over the repetitions of a figure
# from runs.csv, NaN if not run.
value() {
  awk -F, -v m="$1" -v n="$2" -v k="$3" -v f="$4" -v c="$5" '
    NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
    $1 == m && $2 == n && $3 == k && $4 == f && $col[c] != "NaN" { v[++cnt] = $col[c] + 0 }
    END {
      if (!cnt) { print "NaN"; exit }
      for (i = 2; i <= cnt; ++i) for (j = i; j > 1 && v[j - 1] > v[j]; --j) { t = v[j]; v[j] = v[j - 1]; v[j - 1] = t }
      print (cnt % 2 ? v[(cnt + 1) / 2] : (v[cnt / 2] + v[cnt / 2 + 1]) / 2)
    }' "$RUNS"
}

for rep in $(seq 1 "$REPS"); do
  for n in $COUNTS; do
    has_method seq && run seq "$n" 0 0 "$rep"
    has_method simd && run simd "$n" 0 0 "$rep"
    if has_mpi; then
      for k in $CHILDREN; do
        for f in $FRAMES; do
          has_method dist && run dist "$n" "$k" "$f" "$rep"
          has_method hetero && run hetero "$n" "$k" "$f" "$rep"
        done
      done
    fi
    say "repetition $rep: objects $n done ($SECONDS s)"
  done
done

# ---- Charts ------------------------------------------------------------------------------
# chart NAME TITLE XLABEL YLABEL LOGX LOGY NOTE [NOTE2 [NOTE3]] — draws $OUT/NAME.png from $OUT/NAME.csv.
chart() {
  local name=$1 csv=$OUT/$1.csv empty=1
  awk -F, 'NR > 1 { for (i = 2; i <= NF; ++i) if ($i != "NaN") found = 1 } END { exit !found }' "$csv" && empty=0
  gnuplot -e "in='$csv'; out='$OUT/$name.png'; ttl='$2'; xl='$3'; yl='$4'; logx=$5; logy=$6; \
note='$7'; note2='${8:-}'; note3='${9:-}'; ncols=$(head -1 "$csv" | awk -F, '{print NF}'); empty=$empty" "$GP/lines.gp" \
    2> >(grep -v 'Skipping data file with no valid points' >&2)
  say "wrote $OUT/$name.png"
}
note_for() {  # the skip notes that concern the given methods, plus the machine
  local n="" m
  for m in "$@"; do has_method "$m" || n+="$m: not available yet (skipped). "; done
  echo "${n}${SIZE}x${SIZE} random spheres, seed $SEED; $CPU, $CORES cores; $(date +%Y-%m-%d)"
}
OVERSUB="K children = K+1 MPI ranks on $CORES cores: oversubscribed beyond $((CORES - 1)) child"
SIMD_LABELS="SIMD modelled = machine cycles at the profile clock (10 MHz) + host shading; SIMD host = emulator wall time here"
FARM_LABELS="dist/hetero time = hetero SIMD pass (host) + first frame sent to last back; MPI start-up (about 0.3 s) excluded"
max_k=${CHILDREN##* }
f=${FRAMES##* }  # the smallest frame: the paper's best case
oversub() { [ $(($1 + 1)) -gt "$CORES" ] && echo " (oversubscribed)"; return 0; }
add() { awk -v a="$1" -v b="$2" -v s="${3:-1}" 'BEGIN { print (a == "NaN" || b == "NaN") ? "NaN" : a + s * b }'; }
simd_model() { add "$(value simd "$1" 0 0 model_s)" "$(value simd "$1" 0 0 shade_s)"; }

# Fig 5: sequential vs SIMD/sequential.
{ echo "objects,sequential,SIMD/seq (emulator host time),SIMD/seq (modelled machine + host shading)"
  for n in $COUNTS; do
    echo "$n,$(value seq "$n" 0 0 time_s),$(value simd "$n" 0 0 time_s),$(simd_model "$n")"
  done; } >"$OUT/fig05_seq_vs_simd.csv"
chart fig05_seq_vs_simd "Fig 5: sequential vs SIMD/sequential (median of $REPS)" "objects" "seconds" 1 1 \
  "$(note_for seq simd)" "$SIMD_LABELS"

# Fig 6: sequential vs distributed with each number of children (smallest frame).
{ printf "objects,sequential"; for k in $CHILDREN; do printf ",distributed %s children%s" "$k" "$(oversub "$k")"; done; echo
  for n in $COUNTS; do
    printf "%s,%s" "$n" "$(value seq "$n" 0 0 time_s)"
    for k in $CHILDREN; do printf ",%s" "$(value dist "$n" "$k" "$f" time_s)"; done; echo
  done; } >"$OUT/fig06_seq_vs_dist.csv"
chart fig06_seq_vs_dist "Fig 6: sequential vs distributed (frames ${f}x${f}, median of $REPS)" "objects" "seconds" 1 1 \
  "$(note_for seq dist)" "$FARM_LABELS" "$OVERSUB"

# Figs 7-9: heterogeneous vs distributed for each frame size, one chart per child count.
fig=7
for k in $CHILDREN; do
  name=$(printf "fig%02d_hetero_vs_dist_%dchildren" "$fig" "$k")
  { printf "objects"; for fr in $FRAMES; do printf ",distributed %sx%s,heterogeneous %sx%s" "$fr" "$fr" "$fr" "$fr"; done; echo
    for n in $COUNTS; do
      printf "%s" "$n"
      for fr in $FRAMES; do printf ",%s,%s" "$(value dist "$n" "$k" "$fr" time_s)" "$(value hetero "$n" "$k" "$fr" time_s)"; done
      echo
    done; } >"$OUT/$name.csv"
  chart "$name" "Fig $fig: heterogeneous vs distributed, $k children$(oversub "$k") (median of $REPS)" "objects" "seconds" 1 1 \
    "$(note_for dist hetero)" "$FARM_LABELS" "$(oversub "$k" | grep -q . && echo "$OVERSUB")"
  fig=$((fig + 1))
done

# Figs 10 and 11: data flow and pixels processed against frame size (REF_COUNT objects,
# the most children). Bytes and pixels do not depend on timing: one repetition's value.
for what in bytes pixels; do
  if [ $what = bytes ]; then name=fig10_data_flow; ttl="Fig 10: data flow parent<->children"; yl="bytes (both ways, payload + 40-byte envelopes)"
  else name=fig11_pixels; ttl="Fig 11: pixels processed by the children"; yl="pixels"; fi
  { echo "frame size,distributed,heterogeneous"
    for fr in $FRAMES; do
      row="$fr"
      for m in dist hetero; do
        if [ $what = bytes ]; then
          row+=",$(add "$(value "$m" "$REF_COUNT" "$max_k" "$fr" bytes_p2c)" "$(value "$m" "$REF_COUNT" "$max_k" "$fr" bytes_c2p)")"
        else
          row+=",$(value "$m" "$REF_COUNT" "$max_k" "$fr" pixels)"
        fi
      done
      echo "$row"
    done; } >"$OUT/$name.csv"
  chart "$name" "$ttl ($REF_COUNT objects, $max_k children)" "frame size (pixels a side)" "$yl" 1 0 \
    "$(note_for dist hetero)" "counted by the parent (.distributed.traffic, .perChild[].pixels); the image has ${SIZE}x${SIZE} = $((SIZE * SIZE)) pixels"
done

# Fig 12: all four methods (the most children, the smallest frame).
{ echo "objects,sequential,SIMD/seq (emulator host time),SIMD/seq (modelled machine + host shading),distributed $max_k children$(oversub "$max_k"),heterogeneous $max_k children$(oversub "$max_k"),heterogeneous (modelled SIMD pass + farm)"
  for n in $COUNTS; do
    het_model=$(add "$(value hetero "$n" "$max_k" "$f" model_s)" "$(add "$(value hetero "$n" "$max_k" "$f" time_s)" "$(value hetero "$n" "$max_k" "$f" simd_host_s)" -1)")
    echo "$n,$(value seq "$n" 0 0 time_s),$(value simd "$n" 0 0 time_s),$(simd_model "$n"),$(value dist "$n" "$max_k" "$f" time_s),$(value hetero "$n" "$max_k" "$f" time_s),$het_model"
  done; } >"$OUT/fig12_all_methods.csv"
chart fig12_all_methods "Fig 12: the four methods (frames ${f}x${f}, median of $REPS)" "objects" "seconds" 1 1 \
  "$(note_for seq simd dist hetero); $OVERSUB" "$SIMD_LABELS" "$FARM_LABELS"

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
# Fixed against float on the array, with the host tracers (its own script, also run alone).
if [ "$MODE" = quick ]; then FVF=(FRAC=8 FLOATS=e6m12 SAMPLE=1024); else FVF=(SAMPLE="$ACC_SAMPLE"); fi
env "${FVF[@]}" SIZE="$SIZE" COUNT="$REF_COUNT" SEED="$SEED" ZEPHYR="$ZEPHYR" OUT="$OUT" \
  bash "$GP/fixed_vs_float.sh" || skip "fixed vs float chart (tools/charts/fixed_vs_float.sh failed)"
# The recompute share by width (its own script, also run alone): 128x128 (QUICK: 64x64, 2
# widths); SCENES=DIR adds the SPD lattice from DIR.
if [ "$MODE" = quick ]; then RCS=(SIZE=64 FRAC="8 16"); else RCS=(SIZE=128); fi
env "${RCS[@]}" SEED="$SEED" ZEPHYR="$ZEPHYR" OUT="$OUT" SCENES="${SCENES:-}" \
  bash "$GP/recompute.sh" || skip "recompute share chart (tools/charts/recompute.sh failed)"

{ echo "mode,$MODE"; echo "size,$SIZE"; echo "objects,$(tr ' ' ';' <<<"$COUNTS")"
  echo "children,$(tr ' ' ';' <<<"$CHILDREN")"; echo "frames,$(tr ' ' ';' <<<"$FRAMES")"
  echo "seed,$SEED"; echo "repetitions,$REPS (figures are medians)"; echo "accuracy_objects,$REF_COUNT"
  echo "accuracy_frac_bits,$(tr ' ' ';' <<<"$FRAC")"; echo "accuracy_sample_pixels,$ACC_SAMPLE"
  echo "elapsed_s,$SECONDS"; echo "cpu,$CPU"; echo "cores,$CORES"; echo "date,$(date -Iseconds)"
  echo "methods,$(tr -d ' ' <<<"$METHODS" | tr ',' ';')"; echo "skipped,${SKIPPED//,/;}"
} >"$OUT/run_info.csv"
say "done: $OUT (run_info.csv says what ran)"
